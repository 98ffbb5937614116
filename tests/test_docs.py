"""The documentation: the MkDocs site builds with `--strict` (no broken link, missing anchor or missing API
object), its CLI reference lists every flag of every command, every public name documents its parameters
(Google-style `Args:`, as mkdocstrings parses them), and the README stays a front page."""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import inspect
import os
import re
import subprocess
import sys

import pytest

from tests.support.harness import REPO

HAS_MKDOCS = all(importlib.util.find_spec(m) is not None for m in ("mkdocs", "material", "mkdocstrings_handlers"))
# The docstring parser mkdocstrings renders with; reading docstrings needs no site.
HAS_GRIFFE = importlib.util.find_spec("griffe") is not None


def _option_strings(parser: argparse.ArgumentParser) -> set[str]:
    """Every flag and positional name of a parser and its sub-parsers (not -h/--help)."""
    names = set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                names |= _option_strings(child)
        elif not isinstance(action, argparse._HelpAction):
            names |= set(action.option_strings) or {action.dest}
    return names


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    return out, result


@pytest.mark.requires(HAS_MKDOCS, "mkdocs, mkdocs-material and mkdocstrings[python] (pip install '.[docs]')")
def test_the_site_builds_strict_without_a_warning(site):
    out, result = site
    log = result.stdout + result.stderr
    assert result.returncode == 0, log
    assert "WARNING" not in log, log
    assert (out / "index.html").exists() and (out / "api" / "index.html").exists()


@pytest.mark.requires(HAS_MKDOCS, "mkdocs, mkdocs-material and mkdocstrings[python] (pip install '.[docs]')")
def test_the_cli_reference_lists_every_flag_of_every_command(site):
    from langgap.cli.main import build_parser

    out, result = site
    assert result.returncode == 0, result.stderr
    page = (out / "cli" / "index.html").read_text()
    assert "langgap-cli-reference" not in page  # the marker was replaced
    parser = build_parser()
    verbs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for verb in verbs:
        assert f"langgap {verb}</code>" in page, verb
    missing = sorted(name for name in _option_strings(parser) if f"<code>{name}" not in page)
    assert not missing, missing


@pytest.mark.requires(HAS_MKDOCS, "mkdocs, mkdocs-material and mkdocstrings[python] (pip install '.[docs]')")
def test_the_api_page_renders_the_public_names_from_their_docstrings(site):
    import langgap

    out, _ = site
    page = (out / "api" / "index.html").read_text()
    for name in langgap.__all__:
        assert re.search(rf'id="langgap\.[\w.]*\b{name}"', page), name


def _sections(doc: str | None) -> dict[str, set[str]]:
    """The names each section of a Google-style docstring documents (`parameters`, `attributes`, `returns`,
    ...), read by griffe's parser, the one mkdocstrings renders the API page with."""
    from griffe import Docstring, Parser

    found: dict[str, set[str]] = {}
    for section in Docstring(inspect.cleandoc(doc or ""), lineno=1).parse(Parser.google, warn_missing_types=False):
        items = section.value if isinstance(section.value, list) else [section.value]
        found.setdefault(section.kind.value, set()).update(getattr(item, "name", "").lstrip("*") for item in items)
    return found


def _parameters(call) -> list[str]:
    return [name for name in inspect.signature(call).parameters if name not in ("self", "cls")]


def _calls(name: str, value) -> list[tuple[str, object, dict[str, set[str]], tuple[str, ...]]]:
    """(what, the call, its docstring's sections, the sections that may document its parameters) for each way
    a caller calls public `name`: a function; a class's own classmethods and static methods and its constructor
    (a dataclass's fields are its parameters: its Attributes may document them)."""
    if not isinstance(value, type):
        return [(name, value, _sections(value.__doc__), ("parameters",))]
    calls = []
    for attribute, member in vars(value).items():
        if isinstance(member, classmethod | staticmethod) and not attribute.startswith("_"):
            call = getattr(value, attribute)
            calls.append((f"{name}.{attribute}", call, _sections(call.__doc__), ("parameters",)))
    init = vars(value).get("__init__")
    if init is not None and init.__module__ == value.__module__:  # its own (not Protocol's or Exception's)
        kinds = ("parameters", "attributes") if dataclasses.is_dataclass(value) else ("parameters",)
        calls.append((name, value, _sections(value.__doc__), kinds))
    return calls


@pytest.mark.requires(HAS_GRIFFE, "griffe, mkdocstrings' docstring parser (pip install '.[docs]')")
def test_every_public_call_documents_each_parameter_and_what_it_returns():
    import langgap

    checked = set()
    for name in langgap.__all__:
        for what, call, sections, kinds in _calls(name, getattr(langgap, name)):
            documented = set().union(*(sections.get(kind, set()) for kind in kinds))
            missing = [p for p in _parameters(call) if p not in documented]
            assert not missing, f"{what}: no Args line (or Attributes, for a dataclass field) for {missing}"
            returns = inspect.signature(call).return_annotation
            if not isinstance(call, type) and returns not in ("None", None):
                assert "returns" in sections, f"{what}: no Returns section"
            checked.add(what)
    assert {"RunSpec.create", "ExecutionOptions", "evaluate", "load_catalog", "make_policy", "Catalog"} <= checked


@pytest.mark.requires(HAS_MKDOCS, "mkdocs, mkdocs-material and mkdocstrings[python] (pip install '.[docs]')")
def test_the_api_page_tables_the_parameters_of_run_spec_create(site):
    from langgap.engine.spec import RunSpec

    out, _ = site
    page = (out / "api" / "index.html").read_text()
    section = page.split('id="langgap.engine.spec.RunSpec.create"', 1)[1].split('id="langgap.', 1)[0]
    table = section.split('<span class="doc-section-title">Parameters:</span>', 1)[1].split("</table>", 1)[0]
    rows = re.findall(r'<tr class="doc-section-item">\s*<td>\s*<code>(\w+)</code>', table)
    assert rows == _parameters(RunSpec.create) and len(rows) == 11


def test_the_readme_is_a_front_page_whose_links_resolve():
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    first_block = re.search(r"```bash\n(.*?)```", readme, re.S).group(1)
    assert [line.split()[0] for line in first_block.strip().splitlines()] == ["./setup.sh", "./test.sh"]
    targets = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", readme)
    assert targets
    for target in targets:
        if "://" not in target:
            assert (REPO / target).exists(), target
