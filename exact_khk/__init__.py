"""exact_khk — exact certification of Kahan–Hirota–Kimura discretizations.

Quick start (exact rational orbit of the Lie–Poisson family, n = 3):

>>> from exact_khk import LiePoissonSystem, KahanMap
>>> system = LiePoissonSystem.from_vectors(a="1,0,2", b="0,1,0", c="3,1,1")
>>> phi = KahanMap(system.field("f"), eps="1/10")          # fastest exact arithmetic
>>> pts = phi.orbit(["1", "0", "0", "0", "1", "0"], steps=3)
>>> phi.arith.format(pts[1][0])
'72745/57239'
>>> phi.inverse(pts[1]) == pts[0]                          # reversibility, exactly
True

``import exact_khk`` itself is cheap: the names of :data:`__all__` are imported
from their modules on first use (module ``__getattr__``), so that the command
line starts without the numerical libraries a command does not need.
"""

from importlib import import_module as _import_module

TYPE_CHECKING = False  # as typing.TYPE_CHECKING (type checkers read it as True), without importing typing;
# deleted at the end: the namespace holds the public names only
__version__ = "0.1.0"

#: where each public name lives (imported on first access)
_EXPORTS = {
    "exact_khk.arith": ("Arith", "arith_names", "default_arith", "exact_arith_names", "get_arith",
                        "register_arith", "to_fraction"),
    "exact_khk.errors": ("ExactKHKError", "InputError", "NearSingularWarning", "NotRationalError", "PoleError",
                         "SingularStepError", "UndecidedError"),
    "exact_khk.kahan.map": ("KahanMap", "kahan_step", "map_jacobian", "orbit"),
    "exact_khk.parsing": ("parse_rational", "parse_signs", "parse_vector"),
    "exact_khk.systems.catalogue": ("System",),  # with its constructors System.load, System.from_expressions
    "exact_khk.systems.quadratic": ("QuadraticField",),
    "exact_khk.systems.lie_poisson.system": ("LiePoissonField", "LiePoissonSystem", "b0_signs",
                                             "involution_circulant", "rational_sign_patterns"),
    "exact_khk.systems.lie_poisson.invariants": ("Htilde",),
    "exact_khk.certification": ("certify",),
    "exact_khk.certification.records": ("Certificate", "Check"),
    "exact_khk.certification.verify": ("verify",),
    "exact_khk.diagnostics": ("degree_sequence", "find_integrals", "height_growth"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}
#: modules once imported here for their side effects, still reachable as attributes
_MODULES = {"ball": "exact_khk.arith.ball", "cyclo": "exact_khk.arith.cyclotomic"}

__all__ = [  # the names of _EXPORTS (a test checks that they agree), literal for linters
    "Arith", "arith_names", "default_arith", "exact_arith_names", "get_arith", "register_arith", "to_fraction",
    "ExactKHKError", "InputError", "NearSingularWarning", "NotRationalError", "PoleError",
    "SingularStepError", "UndecidedError",
    "KahanMap", "kahan_step", "map_jacobian", "orbit",
    "parse_rational", "parse_signs", "parse_vector",
    "System", "QuadraticField", "LiePoissonField", "LiePoissonSystem", "b0_signs", "involution_circulant",
    "rational_sign_patterns", "Htilde", "Certificate", "Check", "certify", "verify",
    "degree_sequence", "find_integrals", "height_growth", "__version__",
]


def __getattr__(name):
    if name in _WHERE:
        value = getattr(_import_module(_WHERE[name]), name)
    elif name in _MODULES:
        value = _import_module(_MODULES[name])
    else:
        raise AttributeError(f"module 'exact_khk' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(__all__) | set(_MODULES) | {n for n in globals() if n.startswith("__")})


if TYPE_CHECKING:  # for type checkers and linters; at run time the names come from __getattr__
    from exact_khk.arith import (Arith, arith_names, default_arith, exact_arith_names, get_arith, register_arith,
                                 to_fraction)
    from exact_khk.certification import certify
    from exact_khk.certification.records import Certificate, Check
    from exact_khk.certification.verify import verify
    from exact_khk.diagnostics import degree_sequence, find_integrals, height_growth
    from exact_khk.errors import (ExactKHKError, InputError, NearSingularWarning, NotRationalError,
                                  PoleError, SingularStepError, UndecidedError)
    from exact_khk.kahan.map import KahanMap, kahan_step, map_jacobian, orbit
    from exact_khk.parsing import parse_rational, parse_signs, parse_vector
    from exact_khk.systems.catalogue import System
    from exact_khk.systems.lie_poisson.invariants import Htilde
    from exact_khk.systems.lie_poisson.system import (LiePoissonField, LiePoissonSystem, b0_signs,
                                                      involution_circulant, rational_sign_patterns)
    from exact_khk.systems.quadratic import QuadraticField

del TYPE_CHECKING
