"""Policies by name. Adding one: write a module with a class that follows `Policy`, add one line here.

A name may also be `package.module:Class` for a policy outside LangGap: an installed package, or a module in the
working directory (`my_policy:MyPolicy` for ./my_policy.py), as `python -m` would find it.
"""

from __future__ import annotations

import difflib
import importlib
import inspect
import os
import sys

from langgap.errors import LangGapError
from langgap.policies.base import Policy

REGISTRY: dict[str, str] = {
    "noop": "langgap.policies.simple:NoopPolicy",
    "random": "langgap.policies.simple:RandomPolicy",
    "delay": "langgap.policies.simple:DelayPolicy",
    "openpi": "langgap.policies.openpi:OpenpiPolicy",
    "lerobot": "langgap.policies.lerobot:LeRobotPolicy",
    "oracle": "langgap.policies.oracle:OraclePolicy",
    "blind": "langgap.policies.oracle:BlindPolicy",
    "small-bc": "langgap.policies.small_bc.policy:SmallBCPolicy",
    "small-vla": "langgap.policies.small_vla.policy:SmallVLAPolicy",
}


class UnknownPolicyError(LangGapError):
    pass


def policy_class(name: str) -> type:
    """Resolve a registered name or a `module:Class` path to a policy class (imported lazily)."""
    target = REGISTRY.get(name, name if ":" in name else None)
    if target is None:
        close = difflib.get_close_matches(name, REGISTRY, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else f" (known: {', '.join(sorted(REGISTRY))})"
        module, dot, attr = name.rpartition(".")
        if dot and module and attr[:1].isupper():  # `my_policy.MyPolicy`: a class path written as an import
            hint = f"; a policy of your own is named module:Class, with a colon: {module}:{attr}"
        raise UnknownPolicyError(f"unknown policy {name!r}{hint}")
    module_name, _, attr = target.partition(":")
    if name not in REGISTRY and os.getcwd() not in sys.path:
        # After everything installed, so a local file never shadows a package; spawned workers inherit the path.
        sys.path.append(os.getcwd())
    try:
        return getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise UnknownPolicyError(f"cannot load policy {name!r} from {target}: {exc}") from None


def _coerce(value: str, like) -> object:
    """Convert a command-line string to the type of a parameter's annotation or default."""
    kind = like if isinstance(like, type) else type(like)
    if kind is bool:
        if value.lower() in ("1", "true", "yes", "on"):
            return True
        if value.lower() in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"not a boolean: {value!r}")
    if kind in (int, float):
        return kind(value)
    return value


def policy_kwargs(name: str, args: dict[str, str] | None = None) -> dict:
    """Check arguments `args` (strings, or values already of their type) against policy `name`'s constructor and
    convert the strings to its types; a policy class with a static `check_arguments(**kwargs)` checks their values
    too (raising a `LangGapError`; a `PolicyArgumentError` names the argument)."""
    cls = policy_class(name)
    params = inspect.signature(cls).parameters
    kwargs = {}
    for key, value in (args or {}).items():
        if key not in params:
            known = ", ".join(p for p in params if p not in ("self", "args", "kwargs")) or "none"
            raise UnknownPolicyError(f"policy {name!r} has no argument {key!r} (arguments: {known})")
        param = params[key]
        like = param.annotation if isinstance(param.annotation, type) else param.default
        try:
            kwargs[key] = (
                value if like is inspect.Parameter.empty or not isinstance(value, str) else _coerce(value, like)
            )
        except ValueError as exc:
            raise UnknownPolicyError(f"policy {name!r} argument {key}: {exc}") from None
    # A policy may refuse bad arguments it can see without loading anything (a checkpoint path that holds none):
    # refused here, before a run directory exists or a worker starts, not as a failure of every episode.
    if (check := getattr(cls, "check_arguments", None)) is not None:
        check(**kwargs)
    return kwargs


def make_policy(name: str, args: dict[str, str] | None = None) -> Policy:
    """Build policy `name` with its constructor's arguments, given as strings (`{"checkpoint": "bc.safetensors"}`).

    Args:
        name: A registered policy's name (`noop`, `random`, `oracle`, `small-bc`, `openpi`, ...) or the
            `module:Class` path of a policy class (its module may be a file in the current directory).
        args: Constructor arguments as strings, converted to the types of the constructor's annotations or
            defaults (None: none).

    Returns:
        The policy.

    Raises:
        LangGapError: An unknown policy or one that cannot be imported, an argument its constructor does not
            take or that does not convert, or a refusal of its constructor (no checkpoint, no server); a missing
            argument is a `PolicyArgumentError` that names it as the constructor does (`checkpoint`).
    """
    return policy_class(name)(**policy_kwargs(name, args))
