"""The feasibility gate: which tasks are shown doable, and what each verdict rests on.

`validate` (`validation`) runs it: the oracle's episodes, the searches, the probes; `rows` judges each task;
`claims` checks the benchmark's own claims; `probes` are its scene probes as work items; `switch` is the gate
per switch step K; `recording` writes the verdicts beside a registry; `text` renders it all. The search for
demonstrations where the oracle fails (`search`) and the stored demonstrations it finds (`demonstrations`:
saved, replayed, verified), proofs of impossibility (`proofs`) and the verdicts counted (`coverage`).

The gate's episodes, searches and probes are the engine's work, so it sits above the engine; it never imports
the audit (`langgap.audit`). The verdict files themselves are read with the catalog (`langgap.catalog.verdicts`,
`switch_verdicts`): a selection such as `feasible` reads them, so they lie under selection, below this package.
"""

from langgap.gate.validation import Validation, validate

__all__ = ["Validation", "validate"]
