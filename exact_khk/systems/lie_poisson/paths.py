"""The one table of rules by which ``method='auto'`` picks how a step is solved.

A rule stays only where it makes a user-visible command (``orbit``, ``certify``,
``scale``, sweep tasks) at least 1.5× faster than the simpler route without it:
CPU time of whole commands in two source trees, with the rule and without,
alternating, medians of 3 rounds (docs/benchmarks.md, "Rules of the auto path,
measured as whole commands"; the figure after each row is without / with there).
Every route gives the same rational point as the dense solve (tested with ``==``).  The rules depend on what
the field *declares* — whether its step's 2×2 blocks are circulant
(``field.circulant_structure()``, n = dim/2) — on the arithmetic's integer kernel
(``flint``: python-flint; ``gmpy2``: Bareiss elimination) and on n; never on a
family's name.  The table sits beside the steps it chooses among
(:mod:`~exact_khk.systems.lie_poisson.steps`, which a Kahan map asks through
``field.structured_steps``); the constants of its generic rows are defined with the
generic solver they tune: the Dixon row in :mod:`exact_khk.kahan.map`, the κ and
``cyclo:N`` rows in :mod:`exact_khk.linalg.dense` and :mod:`exact_khk.linalg.floating`.

=============================  ==================================================
circulant blocks, integer       split for n ≤ :data:`AUTO_SPLIT_MAX_N` (against the
kernel flint or gmpy2           structured step: ``orbit --n 3 --steps 1000`` 3.72×,
                                n = 4, 5, 6 1.76×, 1.52×, 1.58×; gmpy2 against
                                Bareiss: ``orbit --n 3 --steps 300`` 1.85×); above it
                                structured (flint) or dense (gmpy2)
no structure, or other kernels  dense
dense steps along an orbit      Dixon's output-sensitive solve (python-flint,
                                8 ≤ N < 16) once an answer grew by < 2× and
                                :data:`~exact_khk.kahan.map.SMALL_ANSWER_MIN_BITS` ≤ h <
                                :data:`~exact_khk.kahan.map.DIXON_BITS` · (N − 6)
                                (``orbit --n 5 --method dense --steps 150`` 2.55×)
exact H̃ (flint, rational)       structured at every n
a structured step (and H̃)       2×2 solves over the factors of tⁿ − 1 (``circulant.
                                split_solve``)
a structured step's division    Cramer's rule down the tower (``CirculantRing.norm``)
by d in Z[t]/(tᵐ ∓ 1)           where Cramer's bound H on the answer is small:
                                H ≤ :data:`DIVISION_BY_NORM_MAX_BITS` and
                                b·H ≤ :data:`DIVISION_BY_NORM_MAX_WORK` (b the odd
                                part of m), or m = 1; otherwise the fixed-point
                                division (``CirculantRing.solve``) (``certify --n 8
                                --seed 1`` 1.67×)
floating arithmetics            dense (genuine p-bit arithmetic); ``mp:P``: κ in
                                binary64 where N·κ ≤ :data:`~exact_khk.linalg.floating.BINARY64_CONDITION_MAX`,
                                else κ's ‖M⁻¹‖₁ in p bits from the inverse for
                                N ≤ :data:`~exact_khk.linalg.dense.EXACT_INVERSE_MAX_N`, else estimated
                                (``linalg.dense.solve``) (``orbit --n 16 --arith
                                mp:100 --steps 100`` 1.45×, under 1.5×; kept because it
                                also sets how exact the κ of the warnings is)
exact steps and H̃ in cyclo:N    the exact DFT (:mod:`~exact_khk.systems.lie_poisson.circulant_dft`:
(n | N) and gf:P (n | P − 1)    n 2×2 systems over Q(ζ_N) or F_P, the fields over
                                Q(ω) included), at every n within the memory
                                bounds below (n·φ as m·φ, φ = 1 for gf:P)
linear algebra over Q(ζ_N)      FLINT on the coefficients for φ(N) ≤
(``cyclo:N``)                   :data:`~exact_khk.linalg.dense.CYCLO_REGULAR_MAX_DEGREE`, a solve as one
                                rational system up to size
                                :data:`~exact_khk.linalg.dense.CYCLO_REGULAR_MAX_SIZE`; else the generic loops
                                and elimination; a rational matrix solved over Q
                                (FLINT: ``certify --n 3 --arith cyclo:3`` 2.75×)
degrees on a line over F_p      polynomial arithmetic (Bareiss over ``nmod_poly``)
(``diagnostics.degrees``)       below dimension :data:`DEGREES_BY_VALUES_MIN_DIM`;
                                values at points of the line from it, handing
                                over to polynomial arithmetic once the degrees
                                grow geometrically (``degrees._geometric``) below
                                dimension :data:`DEGREES_HAND_OVER_BELOW_DIM`
                                (values: ``degrees --n 4``, ``--n 6`` 1.92×, 6.97×; the
                                hand-over: 1.59× on a cyclic map at N = 8)
=============================  ==================================================
"""

from exact_khk.linalg import dense

#: the n for which the split step exists (``method='split'``; the generated code grows like
#: the cube of the largest degree φ(d))
SPLIT_N = tuple(range(1, 16))
#: auto takes the split step at every height up to this n, the structured step (flint) or the
#: dense one (gmpy2) above it.  Whole commands, without / with the split step: flint
#: ``orbit --n 3 --steps 1000`` 3.72×, ``--n 4, 5, 6 --seed 1`` to 13 000–30 000 bits 1.76×,
#: 1.52×, 1.58× (n = 2: 1.22–1.36×); gmpy2 ``orbit --n 3 --steps 300`` 1.85×.  Above it no
#: command gained 1.5×: flint n = 7..15 0.89–1.07× (n = 12 0.90×), gmpy2 n = 8, 15 1.08×, 0.67×
AUTO_SPLIT_MAX_N = 6
#: a structured step's division by d over a factor Z[t]/(tᵐ ∓ 1) of tⁿ − 1 is Cramer's rule
#: down the tower (``CirculantRing.norm``, which keeps N and the adjugate A in lowest terms
#: at every level) while Cramer's bound H (bits) is at most this ...
DIVISION_BY_NORM_MAX_BITS = 2 ** 16
#: ... and b·H is at most this, b the odd part of m (where the tower ends in the Galois
#: conjugates, whose cost grows with b); scalar divisions, m = 1, always.  Whole commands,
#: without / with the rule (the fixed-point division for every m > 1): ``certify --n 8 --seed
#: 1`` 1.67×, ``certify --n 16 --seed 1 --steps 2`` 1.38×.  Per division, with the norm
#: in lowest terms (along orbits gcd(N, content A) is most of N: 6 234 of 7 149 bits over
#: t¹⁶ + 1 at n = 32, 434 bits), norm / fixed-point along orbits crosses 1 near
#: H = 70 000 at m = 8, 16, 100 000 at m = 32, 200 000 at m = 64, but near 13 000 at
#: m = 11, 13, 22 000 at m = 9, 15, 45 000 at m = 5·2ᵏ (scripts/bench_division.py at n =
#: 12..256 to 12 000 bits); over 299 divisions this rule's choices cost 1.024× the faster
#: route's (the simpler H ≤ 8192 or m·H ≤ 2¹⁷ 1.064×, 3.3× on single divisions at m = 16,
#: 24, H ≈ 16 500); first steps off small points (Cramer-sized answers) 0.05–0.16 at every
#: m measured
DIVISION_BY_NORM_MAX_WORK = 2 ** 17

#: degree growth (``diagnostics.degrees.line_run``): from this dimension N the degrees come
#: from values at points of the line (one N×N solve per point and step) instead of
#: polynomial arithmetic (O(N³) products of degree ~N·d_k per step).  20 steps of the
#: Lie–Poisson family (linear growth), polynomials / values: 0.3×, 0.9×, 2.5×, 5.6×, 10×,
#: 34×, > 23× at N = 4, 6, 8, 10, 12, 16, 32 (scripts/bench_degrees.py, docs/benchmarks.md); whole
#: commands without / with values: ``degrees --n 4 --seed 1`` 1.92×, ``--n 6`` 6.97× ...
DEGREES_BY_VALUES_MIN_DIM = 8
#: ... but for geometric growth (the cyclic fields, d_k = N^k to max_degree 20 000) values
#: are slower below this dimension: polynomials / values 0.6×, 0.6× at N = 8, 12, 1.1× at
#: 13, 1.8× at 14 (a separate run), 3.3× at 16; below it the run hands over (then
#: polynomials / the rule: 1.0× and 0.9× at N = 8, 12).  The whole command ``degrees`` of the cyclic
#: Kahan map of dimension 8, without / with it: 1.59× (docs/benchmarks.md, rules of the auto path)
DEGREES_HAND_OVER_BELOW_DIM = 13


def exact_dft_fits(ar, n: int) -> bool:
    """Whether the exact DFT of length n in ``ar`` (its transform: an (nφ)² integer matrix,
    φ = 1 for ``gf:P``) is within the memory bounds of the ``cyclo:N`` row
    (:func:`~exact_khk.linalg.dense.coefficients_native` with m = n; ``cyclo:10000`` at n = 20 would need
    (80 000)² entries)."""
    return dense.coefficients_native(ar, n) and n <= dense.CYCLO_REGULAR_MAX_SIZE


def auto_path(n: int, kernel: str, splits: bool, circulant: bool):
    """``(split, structured)`` of ``method='auto'`` for an exact step with integer
    kernel ``kernel`` ('flint', 'gmpy2', …) of a field of dimension 2n whose blocks
    split (``splits``) / are circulant (``circulant``): the rows of the table above."""
    if splits and circulant and n <= AUTO_SPLIT_MAX_N:
        return True, False
    return False, circulant and kernel == "flint"
