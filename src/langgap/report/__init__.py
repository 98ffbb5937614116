"""Reports from stored runs: load → summarize (every number, once) → sections by name (tables, data) → a format by
name."""

from langgap.report.formats import FORMATS, diagnosis_text, format_summary, pooled_text, render
from langgap.report.load import Run, load_runs
from langgap.report.summary import Summary, summarize

__all__ = [
    "FORMATS",
    "Run",
    "Summary",
    "diagnosis_text",
    "format_summary",
    "load_runs",
    "pooled_text",
    "render",
    "summarize",
]
