"""The audit: LangGap's checks of a catalog's tasks, each failure a named finding.

`audit` (`run`) runs the checks over a catalog's selected tasks, or reads them as recorded, and gives an
`AuditResult`; `findings`: the checks that read files, and the findings' storage beside the registry;
`sentences`: a sentence against its goal; `starts`: the simulator checks of tasks read from packages;
`references`: a sentence's referring expressions read and resolved on a scene's layout; `reference_check`:
that resolution on every init state, in the simulator; `page`: the audit as one HTML page.

It reads the catalog and runs the simulator, and never imports the gate (`langgap.gate`); the catalogs read
from packages (`langgap.generation`) record its findings on the files they leave out.
"""

from langgap.audit.run import AuditResult, audit

__all__ = ["AuditResult", "audit"]
