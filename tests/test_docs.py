"""The documentation: the MkDocs site builds with `--strict` (no broken link, missing anchor or missing API
object), its CLI reference lists every flag of every command, and the README stays a front page."""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
import subprocess
import sys

import pytest

from tests.support.harness import REPO

HAS_MKDOCS = all(importlib.util.find_spec(m) is not None for m in ("mkdocs", "material", "mkdocstrings_handlers"))


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
