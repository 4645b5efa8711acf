"""The catalogue: system files shipped with exact_khk (``exact-khk systems`` lists them).

Every ``*.toml`` file in this folder is a system file (``docs/system-files.md``);
its file name without ``.toml`` is its catalogue name and must equal its ``name``
key.  :func:`resolve` accepts a catalogue name or the path of any system file.

>>> all(name == load(name).name for name in names())
True
>>> load("no-such-system")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
exact_khk.errors.InputError: unknown catalogue system 'no-such-system'; available: ...
"""

from __future__ import annotations

import os
from functools import lru_cache
from importlib import resources

from ...errors import InputError
from ..base import System
from ..expressions import ExpressionSystem, load_system


def _files() -> dict:
    """Catalogue name -> resource of its ``.toml`` file."""
    return {p.name[:-5]: p for p in resources.files(__name__).iterdir() if p.name.endswith(".toml")}


def names() -> list:
    """The catalogue names, sorted."""
    return sorted(_files())


def load(name: str) -> ExpressionSystem:
    """The catalogue system ``name`` (parsed once per file content)."""
    files = _files()
    if name not in files:
        raise InputError(f"unknown catalogue system {name!r}; available: {', '.join(sorted(files)) or 'none'}")
    return _parse(name, files[name].read_text(encoding="utf-8"))


@lru_cache(maxsize=None)
def _parse(name: str, text: str) -> ExpressionSystem:
    system = ExpressionSystem.from_toml(text, origin=f"catalogue {name}.toml")
    if system.name != name:
        raise InputError(f"catalogue {name}.toml: its name key {system.name!r} differs from the file name")
    return system


def summary() -> list:
    """[(name, title, dimension, what is known)] for every catalogue system."""
    return [(s.name, s.title, s.dim, s.known()) for s in map(load, names())]


def resolve(spec) -> System:
    """A system from a catalogue name or the path of a system file (a System is returned as is)."""
    if isinstance(spec, System):
        return spec
    if not isinstance(spec, (str, os.PathLike)):
        raise InputError(f"system: expected a catalogue name or a .toml path, got {spec!r}")
    text = os.fspath(spec)
    if text in _files():
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
