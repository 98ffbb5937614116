"""Regenerate the documentation's pictures from the committed code, each stamped with the code it shows.

The stamp is the fingerprint of the picture's source files (tools/picture_stamps.py);
tests/unit/test_docs_pictures.py fails when a picture's stamp differs, i.e. when the picture is stale.

    python -m tools.docs_pictures [report] [reflection]      # from the repository root; no name: all

report: the quick start's runs as setup.sh's main job makes them (oracle and blind on its five
spatial/s0 tasks, 3 episodes, blind filmed once per task and outcome), `langgap report --compare
--summary --html`, opened in Debian's headless Chromium (tests/support/browser.py) at a fixed viewport:
docs/report.png is the page's top (the answer sentences, the stacked outcome bars), docs/report-gallery.png
its gallery of filmed episodes; the summary the command prints is stored, with the same stamp, in
tests/unit/report_outputs/quickstart.summary.md (the README quotes it). reflection: docs/reflection.png,
bench/bench_render.py's agentview with the reflection pass on | off | difference.

The code runs from a temporary `git worktree` of HEAD (PYTHONPATH at its src), so the report's code
version is a commit, never `-dirty`, whatever else the checkout holds; the script refuses to run when
the files a picture shows differ from HEAD's, since the picture would be stale as soon as it is written.
The runs are kept in runs/docs-pictures/ and resumed: a second run re-renders the page only.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from tests.support.browser import CHROMIUM, Page, chromium
from tools.picture_stamps import (
    PICTURES,
    QUICK_START_SUMMARY,
    REPO,
    Picture,
    PictureError,
    fingerprint,
    source_digests,
    stamp_file,
    stamped_text,
)

RUNS = REPO / "runs" / "docs-pictures"
VIEWPORT = {"width": 1280, "height": 1000}
STILL_TRIES = 40
# The quick start's runs (setup.sh's main job; its task list is read from there).
EPISODES, WORKERS = "3", "2"
FILMED = {"blind": ("--video", "per-outcome:1")}

# Resolves once every clip of the page has its first frame (or failed: the error codes are returned).
_CLIPS_LOADED = """(async () => {
  const videos = [...document.querySelectorAll("video")];
  await Promise.all(videos.map(v => v.readyState >= 2 ? null : new Promise(done => {
    v.addEventListener("loadeddata", done); v.addEventListener("error", done); })));
  return videos.map(v => v.error && v.error.code).filter(Boolean);
})()"""
# The page's rectangle from its top to the end of the outcome chart, and the gallery section's (from a margin
# above its heading), in CSS pixels of the document.
_REGIONS = """(() => {
  const box = (element, above) => { const r = element.getBoundingClientRect();
    return {x: 0, y: r.top + scrollY - above, width: document.documentElement.clientWidth, height: r.height + above}; };
  const chart = box(document.getElementById("outcome-chart"), 0);
  return {top: {...chart, y: 0, height: chart.y + chart.height + 16},
          gallery: box(document.querySelector("section.gallery"), 16)};
})()"""


def _git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(REPO), *args], check=True, capture_output=True, text=True).stdout


@contextlib.contextmanager
def committed_tree(pictures: list[Picture]) -> Iterator[Path]:
    """A temporary worktree of HEAD, removed on exit; refuses when a picture's sources differ from HEAD's."""
    tree = Path(tempfile.mkdtemp(prefix="langgap-pictures-")) / "head"
    _git("worktree", "add", "--detach", "--quiet", str(tree), "HEAD")
    try:
        changed = set()
        for picture in pictures:
            here, committed = source_digests(picture), source_digests(picture, tree)
            changed |= {path for path in here.keys() | committed.keys() if here.get(path) != committed.get(path)}
        if changed:
            raise PictureError(
                f"the code the pictures show has uncommitted changes ({', '.join(sorted(changed))}): "
                "commit them first, or the pictures would be stale when written"
            )
        yield tree
    finally:
        _git("worktree", "remove", "--force", str(tree))
        shutil.rmtree(tree.parent, ignore_errors=True)


def _in_tree(tree: Path, argv: list[str]) -> subprocess.CompletedProcess:
    """Run `argv` (after the interpreter) with the worktree's code, its output captured."""
    env = {**os.environ, "PYTHONPATH": str(tree / "src")}
    return subprocess.run([sys.executable, *argv], cwd=tree, env=env, capture_output=True, text=True)


def _checked(result: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    if result.returncode != 0:
        raise PictureError(f"{' '.join(result.args[1:])} failed (exit {result.returncode}):\n{result.stderr}")
    return result


def quick_tasks(tree: Path) -> str:
    """The quick start's tasks, from the `QUICK_TASKS=` lines of setup.sh's main job (later ones extend it)."""
    tasks = ""
    for value in re.findall(r'^QUICK_TASKS="([^"]*)"$', (tree / "setup.sh").read_text(), re.MULTILINE):
        tasks = value.replace("$QUICK_TASKS", tasks)
    if not tasks:
        raise PictureError("setup.sh sets no QUICK_TASKS")
    return tasks


def quick_start_report(tree: Path) -> Path:
    """The quick start's runs (resumed from runs/docs-pictures/) and their HTML report; returns its page."""
    tasks = quick_tasks(tree)
    for policy in ("oracle", "blind"):
        run = RUNS / policy
        argv = ["-m", "langgap.cli.main", "eval", "--policy", policy, "--tasks", tasks, "--episodes", EPISODES]
        argv += ["--workers", WORKERS, "--run", str(run), "--resume", "--quiet", "--no-progress"]
        argv += FILMED.get(policy, ())
        print(f"{policy}: {EPISODES} episodes of each quick-start task (stored ones reused)", flush=True)
        result = _in_tree(tree, argv)
        if result.returncode != 0 and "made with another spec" in result.stderr:
            print(f"{policy}: the stored run has another spec (the catalog changed?): starting afresh", flush=True)
            shutil.rmtree(run)
            result = _in_tree(tree, argv)
        _checked(result)
    page = RUNS / "report"
    shutil.rmtree(page, ignore_errors=True)  # clips of an earlier run must not linger in media/
    report = _checked(_in_tree(tree, ["-m", "langgap.cli.main", "report", str(RUNS / "oracle"), "--compare"]
                               + [str(RUNS / "blind"), "--summary", "--html", str(page)]))  # fmt: skip
    summary = report.stdout.removesuffix(f"wrote {page / 'index.html'}\n")  # the summary, as the quick start prints it
    stamp = fingerprint(next(p for p in PICTURES if p.group == "report"), tree)
    (REPO / QUICK_START_SUMMARY).write_text(stamped_text(summary, stamp), encoding="utf-8")
    print(f"wrote {QUICK_START_SUMMARY}", flush=True)
    return page / "index.html"


def _still_screenshot(page: Page, path: Path, clip: dict) -> None:
    """Screenshot `clip` until two shots in a row are equal: a clip's loading spinner fades out for a second
    after its first frame is shown, and a shot taken meanwhile would show it."""
    previous = None
    for _ in range(STILL_TRIES):
        shot = page.screenshot(path, clip=clip).read_bytes()
        if shot == previous:
            return
        previous = shot
        time.sleep(0.25)
    raise PictureError(f"{path.name}: the page did not come to rest in {STILL_TRIES} screenshots")


def report_pictures(tree: Path) -> None:
    """docs/report.png and docs/report-gallery.png from the quick start's page in headless Chromium."""
    if CHROMIUM is None:
        raise PictureError("Debian's chromium is not installed (./setup.sh installs it)")
    page_file = quick_start_report(tree)
    pictures = {p.path: p for p in PICTURES if p.group == "report"}
    with chromium() as page:
        page.call("Emulation.setDeviceMetricsOverride", **VIEWPORT, deviceScaleFactor=1, mobile=False)
        page.call("Emulation.setScrollbarsHidden", hidden=True)
        page.open(page_file.as_uri())
        if failed := page.evaluate(_CLIPS_LOADED):
            raise PictureError(f"{len(failed)} clip(s) of {page_file} did not load (media error codes {failed})")
        regions = page.evaluate(_REGIONS)
        for name, path in (("top", "docs/report.png"), ("gallery", "docs/report-gallery.png")):
            region = regions[name]
            if region["height"] > VIEWPORT["height"]:
                raise PictureError(f"the page's {name} is taller than the viewport ({region['height']:.0f} px)")
            # Chromium paints video frames only inside the viewport: the region is scrolled to its top.
            page.evaluate(f"window.scrollTo(0, {region['y']})")
            _still_screenshot(page, REPO / path, region)
            stamp_file(REPO / path, fingerprint(pictures[path], tree))
            print(f"wrote {path}", flush=True)
        if page.errors:
            raise PictureError(f"the page logged errors: {page.errors}")


def reflection_picture(tree: Path) -> None:
    """docs/reflection.png from bench/bench_render.py (the reflection comparison only)."""
    picture = next(p for p in PICTURES if p.group == "reflection")
    print("reflection: bench/bench_render.py --no-speed", flush=True)
    result = _checked(_in_tree(tree, ["bench/bench_render.py", "--no-speed", "--png", str(REPO / picture.path)]))
    print(result.stdout, end="")
    stamp_file(REPO / picture.path, fingerprint(picture, tree))
    print(f"wrote {picture.path}", flush=True)


MAKERS = {"report": report_pictures, "reflection": reflection_picture}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("groups", nargs="*", metavar="{report,reflection}", help="the pictures to make (default: all)")
    groups = parser.parse_args(argv).groups or list(MAKERS)
    if unknown := sorted(set(groups) - set(MAKERS)):
        parser.error(f"unknown picture group(s) {', '.join(unknown)} (known: {', '.join(MAKERS)})")
    try:
        with committed_tree([p for p in PICTURES if p.group in groups]) as tree:
            for group in groups:
                MAKERS[group](tree)
    except (PictureError, subprocess.CalledProcessError) as exc:
        detail = exc.stderr.strip() if isinstance(exc, subprocess.CalledProcessError) else exc
        print(f"error: {detail}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
