"""What LangGap knows about its tasks, and how it was shown: the feasibility gate and everything it rests on.

The gate (`validation` runs it: the oracle's episodes, the search, the probes; `rows` judges each task;
`claims` checks the benchmark's own claims; `probes` are its scene probes as work items; `switch_gate` the
gate per switch step K; `recording` writes the verdicts beside a registry; `text` renders it all), the
search for demonstrations where the oracle fails (`search`) and the stored demonstrations it finds
(`demonstrations`: saved, replayed, verified), proofs of impossibility (`proofs`), the audits of a catalog's
tasks (`audit_run`: `audit`, every check run over a selection, or read as recorded; `audit`: findings and
their storage; `sentences`: a sentence against its goal; `starts`: the
simulator checks of tasks read from packages; `references`: a sentence's referring expressions read and
resolved on a scene's layout; `reference_check`: that resolution on every init state, in the simulator;
`audit_page`: the audit as one HTML page) and the verdicts counted (`coverage`).

The verdict files themselves are read with the catalog (`langgap.catalog.verdicts`, `switch_verdicts`): a
selection such as `feasible` reads them, so they lie under selection, below this package.
"""
