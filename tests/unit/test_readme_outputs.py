"""What the README's quick start shows of the report is what `langgap report --summary` prints on the quick
start's runs: its answer sentences and its tables are each found, whole, in that output, as the command that
makes the report's pictures stored it (tests/unit/report_outputs/quickstart.summary.md, stamped with the report
code it came from, so a change to the report's code fails here until it is made again)."""

from __future__ import annotations

import re

from tools.picture_stamps import PICTURES, QUICK_START_SUMMARY, REPO, fingerprint, read_text_stamp

REPORT_PICTURE = next(p for p in PICTURES if p.group == "report")


def quick_start(readme: str) -> str:
    """The README's quick start section, up to the next section."""
    start = readme.index("## Quick start")
    return readme[start : readme.index("\n## ", start)]


def shown_sentences(section: str) -> list[str]:
    """The paragraphs of the section's block quotes, each unwrapped to one line."""
    quoted = "\n".join(line[1:].strip() for line in section.splitlines() if line.startswith(">"))
    return [" ".join(paragraph.split("\n")) for paragraph in re.split(r"\n\n+", quoted.strip()) if paragraph]


def shown_tables(section: str) -> list[str]:
    """The section's Markdown tables, each as its lines."""
    return [m[0] for m in re.finditer(r"(?m)(^\|.*\|\n)+", section)]


def test_the_stored_summary_is_as_new_as_the_report_code():
    stamp, _ = read_text_stamp((REPO / QUICK_START_SUMMARY).read_text(encoding="utf-8"))
    assert stamp == fingerprint(REPORT_PICTURE), (
        f"{QUICK_START_SUMMARY} is older than the report's code: regenerate it with `{REPORT_PICTURE.command}`"
    )


def test_what_the_readme_shows_of_the_summary_is_what_it_prints():
    _, printed = read_text_stamp((REPO / QUICK_START_SUMMARY).read_text(encoding="utf-8"))
    section = quick_start((REPO / "README.md").read_text(encoding="utf-8"))
    sentences, tables = shown_sentences(section), shown_tables(section)
    assert len(sentences) == 2 and sentences[1].startswith("blind")  # one answer per run
    assert tables  # what blind did instead
    paragraphs = printed.split("\n\n")
    for sentence in sentences:
        assert sentence in paragraphs, f"the README's answer is not what the report prints: {sentence}"
    for table in tables:
        assert table in printed, f"the README's table is not one the report prints:\n{table}"


def test_the_excerpts_are_read_whole_from_the_page():
    section = "## Quick start\n\n> first answer\n> wrapped\n>\n> second\n\ntext\n\n| a | b |\n|---|---|\n| 1 | 2 |\n"
    assert shown_sentences(section) == ["first answer wrapped", "second"]
    assert shown_tables(section) == ["| a | b |\n|---|---|\n| 1 | 2 |\n"]
