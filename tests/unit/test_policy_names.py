"""`--policy module:Class` finds a module in the working directory, as the README's `my_policy:MyPolicy` needs."""

from __future__ import annotations

import sys

import pytest

from langgap.policies import UnknownPolicyError, policy_class


def test_a_module_in_the_working_directory_is_found_after_the_installed_ones(tmp_path, monkeypatch):
    (tmp_path / "langgap_doc_policy.py").write_text("class MyPolicy:\n    pass\n")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    assert policy_class("langgap_doc_policy:MyPolicy").__name__ == "MyPolicy"
    assert sys.path[-1] == str(tmp_path)


def test_a_missing_module_is_one_clear_error(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(UnknownPolicyError, match="cannot load policy 'no_such_module:P'"):
        policy_class("no_such_module:P")
