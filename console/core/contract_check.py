"""Checking an object against a ``console.core.contracts`` Protocol: which members it lacks,
which signatures do not fit, and a one-line summary of a capability (what
``console.config.plugins`` says when a registration does not keep its contract)."""

from __future__ import annotations

import inspect
from typing import Any, Protocol


def members(proto: type) -> tuple[str, ...]:
    """The members a Protocol asks for (its own and its Protocol bases'), sorted."""
    names: set[str] = set()
    for base in proto.__mro__:
        if base in (object, Protocol) or not getattr(base, "_is_protocol", False):
            continue
        names.update(getattr(base, "__annotations__", {}))
        for name, value in vars(base).items():
            if name == "__call__" or (
                not name.startswith("_") and (callable(value) or isinstance(value, property))
            ):
                names.add(name)
    return tuple(sorted(names))


def missing(obj: Any, proto: type) -> list[str]:
    """The members of ``proto`` that ``obj`` lacks (a class is checked for its methods
    and class attributes only: instance attributes appear when it is built)."""
    out = []
    for name in members(proto):
        if name == "__call__":
            if not callable(obj):
                out.append("__call__")
            continue
        if inspect.isclass(obj) and _is_data(proto, name):
            continue
        try:
            getattr(obj, name)
        except AttributeError:
            out.append(name)
        except Exception:  # a property that fails before the object is set up is there
            pass
    return out


def _is_data(proto: type, name: str) -> bool:
    for base in proto.__mro__:
        if name in vars(base):
            return isinstance(vars(base)[name], property)
        if name in getattr(base, "__annotations__", {}):
            return True
    return False


def _proto_method(proto: type, name: str) -> Any:
    for base in proto.__mro__:
        v = vars(base).get(name)
        if v is not None and callable(v) and not isinstance(v, property):
            return v
    return None


def signature_problems(obj: Any, proto: type) -> list[str]:
    """Methods of ``obj`` that cannot be called as ``proto`` calls them: a parameter the
    Protocol passes that the method does not take, or one the method requires that the
    Protocol does not pass. ``**kw`` in the Protocol means "the object's own keywords"."""
    out = []
    for name in members(proto):
        want = _proto_method(proto, name)
        if want is None:
            continue
        have = obj if name == "__call__" else getattr(obj, name, None)
        if have is None or not callable(have):
            continue
        try:
            got = inspect.signature(have)
            exp = inspect.signature(want)
        except (TypeError, ValueError):
            continue
        exp_params = list(exp.parameters.values())[1:]  # self
        if inspect.isclass(obj) and name != "__call__":
            got_params = list(got.parameters.values())[1:]
        else:
            got_params = list(got.parameters.values())
        why = _mismatch(exp_params, got_params)
        if why:
            out.append(f"{name}{got} {why}")
    return out


def _mismatch(exp: list[inspect.Parameter], got: list[inspect.Parameter]) -> str:
    P = inspect.Parameter
    positional = [p for p in got if p.kind in (P.POSITIONAL_ONLY, P.POSITIONAL_OR_KEYWORD)]
    var_pos = any(p.kind is P.VAR_POSITIONAL for p in got)
    var_kw = any(p.kind is P.VAR_KEYWORD for p in got)
    by_name = {p.name: p for p in got if p.kind in (P.POSITIONAL_OR_KEYWORD, P.KEYWORD_ONLY)}
    passed: set[str] = set()
    n_pos = 0
    for p in exp:
        if p.kind in (P.POSITIONAL_ONLY, P.POSITIONAL_OR_KEYWORD):
            if n_pos < len(positional):
                passed.add(positional[n_pos].name)
            elif not var_pos:
                return f"does not take {p.name!r} (argument {n_pos + 1})"
            n_pos += 1
        elif p.kind is P.KEYWORD_ONLY:
            if p.name in by_name:
                passed.add(p.name)
            elif not var_kw:
                return f"does not take the keyword {p.name!r}"
    exp_var_kw = any(p.kind is P.VAR_KEYWORD for p in exp)
    for p in got:
        required = p.default is P.empty and p.kind in (
            P.POSITIONAL_ONLY,
            P.POSITIONAL_OR_KEYWORD,
            P.KEYWORD_ONLY,
        )
        if required and p.name not in passed and not exp_var_kw:
            return f"requires {p.name!r}, which the contract does not pass"
    return ""


def summary(proto: type) -> str:
    """What a capability is, in a few words (its docstring up to the first colon)."""
    head = (proto.__doc__ or proto.__name__).strip().split(":")[0].split(".")[0]
    head = " ".join(head.split())
    return head[:1].lower() + head[1:]


def problems(obj: Any, proto: type) -> list[str]:
    """Everything that keeps ``obj`` from satisfying ``proto``: missing members first,
    then methods with the wrong signature."""
    lacking = missing(obj, proto)
    if lacking:
        return [f"no {m}" for m in lacking]
    return signature_problems(obj, proto)


def satisfies(obj: Any, proto: type) -> bool:
    """``obj`` has every member of ``proto``, each method callable as the contract says."""
    return not problems(obj, proto)
