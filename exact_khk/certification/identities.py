"""The family's involution patterns, and results in an exact arithmetic reduced mod P.

* :func:`involution_patterns` — the 2^n − 2 involutions B ≠ ±I; :func:`integral_patterns` — those
  of the n integrals K̃_j (``exact-khk liouville`` checks the claims of the registry on them,
  :mod:`~exact_khk.cli.liouville`);
* :func:`cross_check_mod_p` — orbit points and integrals computed in Q or Q(ζ_N), reduced mod P,
  equal the same computed in gf:P.

>>> involution_patterns(2), integral_patterns(3)
(['+-', '-+'], ['-++', '+-+', '++-'])
"""

from __future__ import annotations

import time

from exact_khk.arith import get_arith
from exact_khk.certification.records import Check
from exact_khk.kahan.map import KahanMap
from exact_khk.parsing import format_signs, parse_signs
from exact_khk.systems.lie_poisson.invariants import Htilde
from exact_khk.systems.lie_poisson.system import nontrivial_sign_patterns


# --- sign patterns -----------------------------------------------------------


def involution_patterns(n: int) -> list[str]:
    """All 2^n − 2 sign patterns of involutions B ≠ ±I."""
    return nontrivial_sign_patterns(n)


def integral_patterns(n: int) -> list[str]:
    """Sign patterns of the n integrals: B_j (sign − at j only), j < n;
    for n = 2, where B_1 = −B_0, the identity ('++', i.e. H̃) and B_1.

    >>> integral_patterns(3), integral_patterns(2)
    (['-++', '+-+', '++-'], ['++', '+-'])
    """
    if n == 2:
        return ["++", "+-"]
    return ["+" * j + "-" + "+" * (n - 1 - j) for j in range(n)]


def _patterns(system, patterns):
    if patterns is None:
        return involution_patterns(system.n)
    return [format_signs(parse_signs(p, system.n)) for p in patterns]


def cross_check_mod_p(system, x0, eps, exact_arith, gf_arith, steps=2, patterns=None,
                      integral_signs=None):
    """Orbit points of Φ_f and of every Φ_g, and the integrals K̃ (of the involutions
    ``integral_signs``, default :func:`integral_patterns`), computed in ``exact_arith``
    (Q or Q(ζ_N)) and reduced mod P equal the same computed directly in ``gf_arith``.

    Returns one :class:`~exact_khk.certification.lie_poisson.Check` (``holds`` False names the first mismatch).
    A :class:`~exact_khk.arith.cyclotomic.BadReductionError` is raised where the reduction
    is undefined (a denominator divisible by P).
    """
    ex, gf = get_arith(exact_arith), get_arith(gf_arith)
    t0 = time.perf_counter()
    pats = _patterns(system, patterns)
    fields = [system.field("f")] + [system.field_for_signs(s) for s in pats]
    ints = [system.field_for_signs(s) for s in (integral_signs or integral_patterns(system.n))]
    mismatch = ""
    for fld in fields:
        a = KahanMap(fld, eps, ex).orbit(x0, steps)
        b = KahanMap(fld, eps, gf).orbit(x0, steps)
        for k, (p, q) in enumerate(zip(a, b)):
            vals = [(f"{fld.label} step {k} coordinate {i}", s, t) for i, (s, t) in enumerate(zip(p, q))]
            vals += [(f"K~_{j}({fld.label} step {k})", Htilde(h, p, eps, ex), Htilde(h, q, eps, gf))
                     for j, h in enumerate(ints)]
            mismatch = next((f"{lab}: {ex.format(s)} -> {gf.format(gf.convert(s))} != {gf.format(t)}"
                             for lab, s, t in vals if gf.convert(s) != t), "")
            if mismatch:
                break
        if mismatch:
            break
    return Check("cross-check", f"results in {ex.name} reduced mod {gf.P} equal results in {gf.name}",
                       True, not mismatch, mismatch or "0", f"{ex.name},{gf.name}",
                       time.perf_counter() - t0,
                       f"exact: every coordinate and integral at {steps + 1} orbit points of "
                       f"{len(fields)} maps")
