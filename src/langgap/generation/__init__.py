"""Making registries: the full same-scene task space (`generate`: each candidate of `candidates`, written by
`registry_writer`), `langgap-beyond` (`beyond`, its sentences in `rewording`), the field's benchmarks read from
their packages (`external`), and the identity that lets a task take another's gate verdict (`identity`).
`langgap generate` runs them; the catalogs they write are loaded by `langgap.catalog`."""
