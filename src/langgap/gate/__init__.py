"""The feasibility gate, a module per job: `validation` runs it (the oracle's episodes, the search, the
probes) and `rows` judges each task; `claims` checks the benchmark's own claims; `probes` are its scene
probes as work items; `recording` writes the verdicts beside a registry; `text` renders it all."""
