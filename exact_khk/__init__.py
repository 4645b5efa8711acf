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
"""

__version__ = "0.1.0"

from exact_khk.arith import Arith, arith_names, default_arith, exact_arith_names, get_arith, register_arith
from exact_khk.arith import ball  # noqa: E402,F401  (registers the ball:P arithmetic)
from exact_khk.arith import cyclotomic as cyclo  # noqa: E402,F401  (registers the cyclo:N and gf:P arithmetics)
from exact_khk.errors import (ExactKHKError, InputError, NearSingularWarning, NotRationalError,
                     PoleError, SingularStepError, UndecidedError)
from exact_khk.kahan.map import KahanMap, kahan_step, map_jacobian, orbit
from exact_khk.parsing import parse_rational, parse_signs, parse_vector
from exact_khk.systems.base import System
from exact_khk.systems.quadratic import QuadraticField
from exact_khk.systems.lie_poisson.system import (LiePoissonField, LiePoissonSystem, b0_signs, involution_circulant,
                      rational_sign_patterns)
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.certification import certify
from exact_khk.certification.records import Certificate, Check

__all__ = [
    "Arith", "arith_names", "default_arith", "exact_arith_names", "get_arith", "register_arith",
    "ExactKHKError", "InputError", "NearSingularWarning", "NotRationalError", "PoleError",
    "SingularStepError", "UndecidedError",
    "KahanMap", "kahan_step", "map_jacobian", "orbit",
    "parse_rational", "parse_signs", "parse_vector",
    "System", "QuadraticField", "LiePoissonField", "LiePoissonSystem", "b0_signs", "involution_circulant",
    "rational_sign_patterns", "Htilde", "Certificate", "Check", "certify", "__version__",
]
