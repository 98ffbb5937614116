"""The audit of a catalog as one self-contained HTML page people can cite (`langgap tasks audit --html DIR`).

Each finding gets its meaning, how many tasks have it, and one row per task with its evidence: the
package file and its SHA-256, the init states file and the SHA-256 of its states, the sentence the file
states and the one its runner sends, what the check measured, and the command that reproduces it. The
page embeds the same data as JSON and fetches nothing: it opens from `file://`.
"""

from __future__ import annotations

import html
import json
from collections.abc import Iterable

from langgap.audit.findings import CHECKS, FINDINGS, Finding, duplicate_counts_text
from langgap.catalog.catalog import Catalog
from langgap.catalog.task import PACKAGE_STYLE, Task
from langgap.page_style import PAGE_STYLE
from langgap.vocabulary import InstructionStyle

_STYLE = (
    PAGE_STYLE
    + """
th, td { vertical-align: top; overflow-wrap: anywhere; }
th { background: #f3f3f3; }
code, .sha { font-family: ui-monospace, monospace; font-size: .85em; word-break: break-all; }
dl.about > dt { font-weight: bold; margin-top: .5em; }
dl.about dl { display: grid; grid-template-columns: max-content auto; gap: .1em 1em; margin: 0; }
dl.about dl > dt { color: #555; }
dl.about dl > dd { margin: 0; }
dl.about ul { margin: 0; padding-left: 1.2em; }
"""
)

_SCRIPT = """
document.querySelectorAll("input.filter").forEach(input => input.addEventListener("input", () => {
  const text = input.value.toLowerCase();
  input.nextElementSibling.querySelectorAll("tbody tr").forEach(row => {
    row.hidden = !row.textContent.toLowerCase().includes(text);
  });
}));
"""


def reproduce_command(catalog: str, finding: Finding, about: dict) -> str:
    """The command that makes `finding` again (`catalog` as the user names it): the audit of its task, with the
    simulator's start or reference check on the recorded number of init states for the findings those checks
    make; reading the package again for a file left out."""
    if finding.name == "unreadable":
        return f"langgap generate --catalog {catalog} --out {catalog}-again.yaml"
    command = f"langgap tasks audit --catalog {catalog} --tasks '{finding.task}'"
    for check in ("starts", "references"):
        if finding.name in CHECKS[check]:
            inits = max((how.get("inits", 0) for how in about.get(check, {}).values()), default=50)
            command += f" --{check} {inits}"
    return command


def _check_of(name: str) -> str:
    return next(check for check, names in CHECKS.items() if name in names)


def _evidence(task: Task | None) -> dict[str, str]:
    """The files and sentences behind a task's findings (empty for a task left out of the catalog)."""
    if task is None:
        return {}
    evidence = {"sentence": task.instruction(InstructionStyle.PAPER)}
    if PACKAGE_STYLE in task.instructions:
        evidence["runner sends"] = task.instruction(PACKAGE_STYLE)
    if task.origin is not None:
        evidence |= {
            "file": f"{task.origin.package} {task.origin.version}: {task.origin.file}",
            "file SHA-256": task.origin.sha256,
            "init states": task.origin.init_file,
            "init states SHA-256": task.origin.init_sha256,
        }
        if task.origin.registered is not None:
            evidence["in its runner's task map"] = "yes" if task.origin.registered else "no"
    return evidence


def audit_data(
    catalog: Catalog, named: str, catalog_hash: str, findings: Iterable[Finding], checked: Iterable[str], about: dict
) -> dict:
    """The page's content as JSON data: the catalog (`named` as the user names it) and its hash, how each check
    ran, and every finding with the check that made it, its evidence and the command that reproduces it."""
    ids = {t.id for t in catalog}
    return {
        "catalog": catalog.name,
        "catalog_hash": catalog_hash,
        "checked": sorted(set(checked)),
        "about": about,
        "findings": [
            {
                "name": f.name,
                "task": f.task,
                "detail": f.detail,
                "check": _check_of(f.name),
                "evidence": _evidence(catalog.get(f.task) if f.task in ids else None),
                "command": reproduce_command(named, f, about),
            }
            for f in findings
        ],
    }


def _anchor(name: str) -> str:
    return name.replace(" ", "-")


# What each recorded setting of a check is, in words (`about`'s keys; others are shown as they are).
_SETTINGS = {
    "inits": "init states checked, from 0",
    "seed": "seed",
    "margin_m": "margin (m): two objects nearer than this fit a comparison equally well",
    "between_ends": "between: how far past either landmark, in lengths of the segment joining them",
    "between_width": "between: how far off that segment, in its lengths",
    "viewpoints": "viewpoints",
    "judged": "expressions judged",
    "unread": "expressions not read",
    "unread_examples": "expressions not read, the first",
    "packages": "packages read",
    "duplicate instructions": "language variants sharing a sentence with another of their source",
    "templates": "tasks by sentence template",
}
# Checks whose settings are recorded per task selection (`--tasks`).
_BY_SELECTION = ("starts", "references")


def about_html(about: dict) -> str:
    """How each check ran (`audit_data`'s `about`), as a definition list: per check, per task selection where
    the check records one, each setting named in words with its value."""
    e = html.escape
    parts = ["<dl class='about'>"]
    for check, how in sorted(about.items()):
        shown = {f"tasks {selection!r}": settings for selection, settings in how.items()}
        parts.append(f"<dt>{e(check)}</dt><dd>{_value_html(shown if check in _BY_SELECTION else how)}</dd>")
    parts.append("</dl>")
    return "".join(parts)


def _value_html(value) -> str:
    """A recorded value: a mapping as a definition list of its settings, a list as a list, else its text."""
    e = html.escape
    if isinstance(value, dict):
        items = "".join(f"<dt>{e(_SETTINGS.get(k, k))}</dt><dd>{_value_html(v)}</dd>" for k, v in value.items())
        return f"<dl>{items}</dl>"
    if isinstance(value, list):
        if all(not isinstance(v, dict | list) and len(str(v)) < 40 for v in value):
            return e(", ".join(map(str, value))) or "none"
        return "<ul>" + "".join(f"<li>{_value_html(v)}</li>" for v in value) + "</ul>"
    return e(str(value))


def finding_heading(name: str, rows: list[dict]) -> str:
    """A finding's section heading: how many tasks have it, and for duplicate instructions how they were
    compared (case-insensitively, since a runner that lowercases sends the same sentence) and how many are
    duplicates as exact strings too."""
    tasks = len({f["task"] for f in rows})
    heading = f"{name}: {tasks} task(s)"
    if name == "duplicate instruction":
        exact = len({f["task"] for f in rows if f["detail"].startswith("same instruction as")})
        heading += f", sentences compared case-insensitively ({exact} of them the same as exact strings too)"
    return heading


def _rows(rows: list[dict]) -> list[str]:
    """One table row per finding: the task, what the check found, its evidence, the command."""
    e = html.escape
    parts = []
    for f in rows:
        evidence = "<br>".join(
            f"{e(k)}: <span class='{'sha' if 'SHA' in k else 'value'}'>{e(v)}</span>" for k, v in f["evidence"].items()
        )
        parts.append(
            f"<tr><td>{e(f['task'])}</td><td>{e(f['detail'])}</td><td>{evidence}</td>"
            f"<td><code class='command'>{e(f['command'])}</code></td></tr>"
        )
    return parts


def audit_page(data: dict) -> str:
    """The self-contained HTML page of `audit_data`."""
    e = html.escape
    found = data["findings"]
    counts = {name: len({f["task"] for f in found if f["name"] == name}) for name in FINDINGS}
    with_findings = len({f["task"] for f in found})
    parts = [
        f"<h1>LangGap audit — {e(data['catalog'])}</h1>",
        f"<p>Registry SHA-256 <span class='sha'>{e(data['catalog_hash'])}</span>. "
        f"{len(data['checked'])} tasks checked: {with_findings} with findings, "
        f"{len(data['checked']) - with_findings} with none.</p>",
        "<h2>How the checks ran</h2>",
        about_html(data["about"]),
    ]
    duplicates = data["about"].get("files", {}).get("duplicate instructions")
    if duplicates:
        parts.append(f"<p>{e(duplicate_counts_text(duplicates))}.</p>")
    parts.append("<h2>Findings</h2><table class='summary'><thead><tr>")
    parts.append("<th>finding</th><th>tasks</th><th>what it means</th></tr></thead><tbody>")
    for name, meaning in FINDINGS.items():
        if counts[name]:
            link = f"<a href='#{e(_anchor(name))}'>{e(name)}</a>"
            parts.append(f"<tr><td>{link}</td><td>{counts[name]}</td><td>{e(meaning)}</td></tr>")
    parts.append("</tbody></table>")
    for name, meaning in FINDINGS.items():
        rows = [f for f in found if f["name"] == name]
        if not rows:
            continue
        parts.append(f"<section class='finding' data-name='{e(name)}'><h2 id='{e(_anchor(name))}'>")
        parts.append(f"{e(finding_heading(name, rows))}</h2><p class='note'>{e(meaning)}</p>")
        parts.append("<input class='filter' placeholder='filter rows'><table class='tasks'><thead><tr>")
        parts.append("<th>task</th><th>what the check found</th><th>evidence</th><th>reproduce</th></tr>")
        parts.append("</thead><tbody>")
        parts += _rows(rows)
        parts.append("</tbody></table></section>")
    payload = json.dumps(data, sort_keys=True).replace("</", "<\\/")
    return (
        "<!doctype html><html lang='en'><head><meta charset='utf-8'>"
        f"<title>LangGap audit — {e(data['catalog'])}</title><style>{_STYLE}</style></head><body>"
        + "".join(parts)
        + f"<script type='application/json' id='audit-data'>{payload}</script><script>{_SCRIPT}</script>"
        + "</body></html>\n"
    )
