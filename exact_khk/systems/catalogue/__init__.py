"""The catalogue: system files shipped with exact_khk (``exact-khk systems`` lists them).

Every ``*.toml`` file in this folder is a system file (``docs/system-files.md``);
its file name without ``.toml`` is its catalogue name and must equal its ``name``
key.  A system with a size or a parameter is a member of a family of
:mod:`.families`, named ``NAME:K=V[,K=V]`` (``volterra-periodic:N=5``); its
generator returns the table of a system file, read by the same reader.
:func:`resolve` accepts a catalogue name, a family member or the path of any system file.

>>> all(name == load(name).name for name in names())
True
>>> load("volterra-periodic:N=7").dim
7
>>> load("no-such-system")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
exact_khk.errors.InputError: unknown catalogue system 'no-such-system'; available: ...
>>> load("volterra-periodic:N=1")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
exact_khk.errors.InputError: 'volterra-periodic:N=1': N=1 is outside 3..40; volterra-periodic takes N = 3..40 ...
"""

from __future__ import annotations

import os
from functools import lru_cache
from importlib import resources

from ...errors import InputError
from ..base import System
from ..expressions import ExpressionSystem, load_system
from . import families


def _files() -> dict:
    """Catalogue name -> resource of its ``.toml`` file."""
    return {p.name[:-5]: p for p in resources.files(__name__).iterdir() if p.name.endswith(".toml")}


def names() -> list:
    """The catalogue names, sorted: every file, and the listed members of every family."""
    return sorted([*_files(), *families.listed()])


def load(name: str) -> ExpressionSystem:
    """The catalogue system ``name`` (parsed once per file content), or the family member
    ``NAME:K=V[,K=V]`` (built once per parameters)."""
    files = _files()
    if name in files:
        return _parse(name, files[name].read_text(encoding="utf-8"))
    if name.partition(":")[0] in families.FAMILIES:
        family, params = families.parse(name)
        return _member(family, tuple(params.items()))
    raise InputError(f"unknown catalogue system {name!r}; available: {', '.join(names()) or 'none'}"
                     f" (families take NAME:K=V, see 'exact-khk systems')")


@lru_cache(maxsize=64)
def _member(family: str, params: tuple) -> ExpressionSystem:
    name = families.member_name(family, dict(params))
    return ExpressionSystem(families.table(family, dict(params)), origin=f"catalogue {name}")


@lru_cache(maxsize=None)
def _parse(name: str, text: str) -> ExpressionSystem:
    system = ExpressionSystem.from_toml(text, origin=f"catalogue {name}.toml")
    if system.name != name:
        raise InputError(f"catalogue {name}.toml: its name key {system.name!r} differs from the file name")
    return system


def summary() -> list:
    """[(name, title, dimension, what is known)] for every catalogue system."""
    return [(s.name, s.title, s.dim, s.known()) for s in map(load, names())]


def literature_summary() -> list:
    """[(name, dimension, reference, integrable, integrals)] for every catalogue system:
    what its ``[literature]`` table says about the Kahan map."""
    return [(s.name, s.dim, s.literature.get("reference", ""), s.literature.get("integrable", "unknown"),
             s.literature.get("integrals", "unknown")) for s in map(load, names())]


def family_summary() -> list:
    """[(family, its parameters and their ranges, description)]."""
    return [(f, families.describe_parameters(f), spec[3]) for f, spec in families.FAMILIES.items()]


def resolve(spec) -> System:
    """A system from a catalogue name or the path of a system file (a System is returned as is)."""
    if isinstance(spec, System):
        return spec
    if not isinstance(spec, (str, os.PathLike)):
        raise InputError(f"system: expected a catalogue name or a .toml path, got {spec!r}")
    text = os.fspath(spec)
    if text in _files() or text.partition(":")[0] in families.FAMILIES:
        return load(text)
    if text.endswith(".toml") or os.sep in text or os.path.exists(text):
        return load_system(text)
    raise InputError(f"system: {text!r} is neither a catalogue system (available: "
                     f"{', '.join(names()) or 'none'}) nor a .toml file")


#: the families of systems given by parameters, by the JSON's ``"family"`` key: (module, class)
FAMILIES = {"lie-poisson": ("exact_khk.systems.lie_poisson.system", "LiePoissonSystem")}


def family(name: str):
    """The class of the family ``name`` (InputError naming the known ones)."""
    import importlib

    if name not in FAMILIES:
        raise InputError(f"system.family: unknown family {name!r}; known: {', '.join(map(repr, FAMILIES))}")
    module, cls = FAMILIES[name]
    return getattr(importlib.import_module(module), cls)


def from_json(d: dict) -> System:
    """A system from its JSON (``System.to_json``): a family's when ``d`` has a ``"family"``
    key, else a system file's (:meth:`ExpressionSystem.from_json`)."""
    if "family" not in d:
        return ExpressionSystem.from_json(d)
    return family(d["family"]).from_json(d)


def from_spec(d: dict) -> System:
    """A family's system from a sweep's spec ``{"family": NAME, ...}`` (its ``from_spec``)."""
    return family(d["family"]).from_spec(d)


# The interface's constructors, with their implementations (systems/base imports none of them).
System.load = staticmethod(resolve)
System.from_expressions = staticmethod(ExpressionSystem.from_expressions)
