"""The one table of rules by which ``method='auto'`` picks how a step is solved.

Every rule here was measured along exact orbits (docs/benchmarks.md,
docs/benchmarks_tall.md) and kept only where it buys at least 20 % somewhere;
every fast path gives the same rational point as the dense solve (tested with
``==``).  The rules depend on what the field *declares* — whether its step's
2×2 blocks are circulant (``field.circulant_structure()``, n = dim/2) — on the
arithmetic's integer kernel (``flint``: python-flint; ``gmpy2``: Bareiss
elimination) and on the point's height h (bits of its largest numerator or
denominator); never on a family's name.  The table sits beside the steps it
chooses among (:mod:`~exact_khk.systems.lie_poisson.steps`, which a Kahan map asks
through ``field.structured_steps``); the constants of its generic rows are defined
with the generic solver they tune: the Dixon row in :mod:`exact_khk.kahan.map`, the
κ and ``cyclo:N`` rows in :mod:`exact_khk.linalg.dense` and
:mod:`exact_khk.linalg.floating`.

=============================  ==================================================
circulant blocks, kernel gmpy2  split for n in :data:`SPLIT_N` (Bareiss is
                                1.7–100× slower)
circulant blocks, kernel flint  split for n in :data:`AUTO_SPLIT_N`;
                                split below :data:`AUTO_SPLIT_BELOW` [n] bits, then
                                structured (n = 7, 8, 9, 10, 15);
                                dense below :data:`DENSE_BELOW` [n] bits, then
                                structured (n = 11, 13);
                                structured from the first step for every other n
                                (n = 14 and n ≥ 16)
no structure, or other kernels  dense
dense steps along an orbit      Dixon's output-sensitive solve (python-flint,
                                8 ≤ N < 16) once an answer grew by < 2× and
                                :data:`~exact_khk.kahan.map.SMALL_ANSWER_MIN_BITS` ≤ h <
                                :data:`~exact_khk.kahan.map.DIXON_BITS` · (N − 6)
exact H̃ (flint, rational)       structured for n ≥ :data:`HTILDE_STRUCTURED_MIN_N`
a structured step (and H̃)       2×2 solves over the factors of tⁿ − 1 (``circulant.
                                split_solve``), but one over Z[t]/(tⁿ − 1) for points of
                                height h with n²·h ≤ :data:`UNSPLIT_MAX_WORK`
a structured step's division    Cramer's rule down the tower (``CirculantRing.norm``)
by d in Z[t]/(tᵐ ∓ 1)           where Cramer's bound H on the answer is small:
                                H ≤ :data:`DIVISION_BY_NORM_MAX_BITS` and
                                b·H ≤ :data:`DIVISION_BY_NORM_MAX_WORK` (b the odd
                                part of m), or m = 1; otherwise the fixed-point
                                division (``CirculantRing.solve``)
floating arithmetics            dense (genuine p-bit arithmetic); ``mp:P``: κ in
                                binary64 where N·κ ≤ :data:`~exact_khk.linalg.floating.BINARY64_CONDITION_MAX`,
                                else κ's ‖M⁻¹‖₁ in p bits from the inverse for
                                N ≤ :data:`~exact_khk.linalg.dense.EXACT_INVERSE_MAX_N`, else estimated
                                (``linalg.dense.solve``)
exact steps and H̃ in cyclo:N    the exact DFT (:mod:`~exact_khk.systems.lie_poisson.circulant_dft`:
(n | N) and gf:P (n | P − 1)    n 2×2 systems over Q(ζ_N) or F_P, the fields over
                                Q(ω) included): steps for n ≥
                                :data:`EXACT_DFT_STEP_MIN_N`, H̃ for every n; within
                                the memory bounds below (n·φ as m·φ, φ = 1 for gf:P)
linear algebra over Q(ζ_N)      FLINT on the coefficients for φ(N) ≤
(``cyclo:N``)                   :data:`~exact_khk.linalg.dense.CYCLO_REGULAR_MAX_DEGREE`, a solve as one
                                rational system up to size
                                :data:`~exact_khk.linalg.dense.CYCLO_REGULAR_MAX_SIZE`; else the generic loops
                                and elimination; a rational matrix solved over Q
degrees on a line over F_p      polynomial arithmetic (Bareiss over ``nmod_poly``)
(``diagnostics.degrees``)       below dimension :data:`DEGREES_BY_VALUES_MIN_DIM`;
                                values at points of the line from it, handing
                                over to polynomial arithmetic once the degrees
                                grow geometrically (``degrees._geometric``) below
                                dimension :data:`DEGREES_HAND_OVER_BELOW_DIM`
=============================  ==================================================
"""

from exact_khk.linalg import dense

#: the n for which the split step exists (the generated code grows like the cube
#: of the largest degree φ(d); for n ≥ 16 the structured step is as fast)
SPLIT_N = tuple(range(1, 16))
#: flint: split at every height (split / structured along orbits at 5 000–30 000 bits:
#: 0.29–0.36, 0.60–0.69, 0.36–0.45 for n = 4, 5, 6; 0.49–1.04 for n = 12 at 560–20 000 bits,
#: where a height rule would buy at most 4 %; scripts/bench_split_height.py)
AUTO_SPLIT_N = (1, 2, 3, 4, 5, 6, 12)
#: flint: split below these heights, where the structured step overtakes it (bench.py's
#: crossover table, 4 orbit steps: split / structured = 1 near 1700 and 750 bits for n = 7,
#: 15, near 3500 bits for n = 9 (1.17× at 6099 bits, one step 1.23× and 1.52× at 10 000 and
#: 20 000 bits), near 2000 bits for n = 8 (1.17–1.33 at 2 575–30 000 bits); n = 10 crosses
#: near 1 500 bits but the structured step is at most 1.2× faster up to 6 000 bits.  n = 14
#: is structured from the first step: split / structured 0.90 at its first point and
#: 1.18–2.57 from 326 bits, and no split code to generate)
AUTO_SPLIT_BELOW = {7: 2048, 8: 2048, 9: 3584, 10: 5120, 15: 768}
#: flint: dense below these heights, then structured, for the n = 11, 13 that the split step
#: serves poorly (factors of degree 10, 12) (4 orbit steps: dense / structured = 1 near 550
#: bits for n = 11 and 450 bits for n = 13; dense 0.77–0.82× at 2–268 bits for n = 11 and
#: 0.80–0.95× at 2–306 bits for n = 13); every other n without a rule above is
#: structured from the first step (n = 14 and n ≥ 16: faster than a dense step even once
#: that is built: dense / structured 1.5 over 4 orbit steps from n = 14's first point, one
#: step 447 against 177 µs at n = 16's; a dense step's first call also builds the field's
#: integer system, 10 ms at n = 32)
DENSE_BELOW = {11: 512, 13: 512}
#: exact H̃ by the structured solve from this n (10×, 164×, 567× faster than dense at orbit points,
#: n = 3, 8, 16: docs/benchmarks.md, "H̃ at orbit points")
HTILDE_STRUCTURED_MIN_N = 3
#: a structured step (and H̃) solves over Z[t]/(tⁿ − 1) unsplit for points of height h (bits
#: of the largest numerator or the common denominator) with n²·h at most this: there the
#: fixed costs of the ~log₂ n factors' solves outweigh the unsplit solve's Cramer-sized
#: arithmetic (~n²·h).  One step at random points of 1–64 bits, unsplit / split
#: (docs/benchmarks.md, "Small points unsplit"): n = 16: 0.51–0.80 to 32 bits, 0.88 at 64;
#: n = 24: 0.66–0.80 to 8 bits, 0.76–1.08 from 16; n = 32: 0.65–0.81 to 8 bits, 0.85–1.09
#: from 16; n = 64: 0.89 at 1 bit, 0.96–3.26 from 4; n = 128: 1.07–3.74 from 1 bit
UNSPLIT_MAX_WORK = 8192
#: a structured step's division by d over a factor Z[t]/(tᵐ ∓ 1) of tⁿ − 1 is Cramer's rule
#: down the tower (``CirculantRing.norm``, which keeps N and the adjugate A in lowest terms
#: at every level) while Cramer's bound H (bits) is at most this ...
DIVISION_BY_NORM_MAX_BITS = 2 ** 16
#: ... and b·H is at most this, b the odd part of m (where the tower ends in the Galois
#: conjugates, whose cost grows with b); scalar divisions, m = 1, always.  With the norm
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
#: 34×, > 23× at N = 4, 6, 8, 10, 12, 16, 32 (scripts/bench_degrees.py, docs/benchmarks.md) ...
DEGREES_BY_VALUES_MIN_DIM = 8
#: ... but for geometric growth (the cyclic fields, d_k = N^k to max_degree 20 000) values
#: are slower below this dimension: polynomials / values 0.6×, 0.6× at N = 8, 12, 1.1× at
#: 13, 1.8× at 14 (a separate run), 3.3× at 16; below it the run hands over (then
#: polynomials / the rule: 1.0× and 0.9× at N = 8, 12)
DEGREES_HAND_OVER_BELOW_DIM = 13


#: exact steps by the DFT in ``cyclo:N`` (n | N) and ``gf:P`` (n | P − 1) from this n: against
#: the dense solve at an orbit point of g[+-+…+] one step is 1.5–13× faster in cyclo:n and
#: 1.2–9× in gf:P at n = 3..12, but 0.7–0.85× at n = 2 in cyclo:2, 4, 6 (the dense system is
#: then only 4φ wide) and 1.0× in gf:P; H̃ by the DFT is faster at every n (1.9× at n = 2,
#: 3.5–33× at n = 3..12), so it has no rule (scripts/bench_cyclo_dft.py, docs/benchmarks.md)
EXACT_DFT_STEP_MIN_N = 3


def exact_dft_fits(ar, n: int) -> bool:
    """Whether the exact DFT of length n in ``ar`` (its transform: an (nφ)² integer matrix,
    φ = 1 for ``gf:P``) is within the memory bounds of the ``cyclo:N`` row
    (:func:`~exact_khk.linalg.dense.coefficients_native` with m = n; ``cyclo:10000`` at n = 20 would need
    (80 000)² entries)."""
    return dense.coefficients_native(ar, n) and n <= dense.CYCLO_REGULAR_MAX_SIZE


def auto_path(n: int, kernel: str, splits: bool, circulant: bool):
    """``(split, structured, switch_bits)`` of ``method='auto'`` for an exact step
    with integer kernel ``kernel`` ('flint', 'gmpy2', …) of a field of dimension 2n
    whose blocks split (``splits``) / are circulant (``circulant``): the rows of
    the table above.  ``switch_bits``: the height from which the structured step
    takes over (0: from the start, if ``structured``)."""
    if splits and circulant:
        if kernel != "flint" or n in AUTO_SPLIT_N:
            return True, False, 0
        if n in AUTO_SPLIT_BELOW:
            return True, True, AUTO_SPLIT_BELOW[n]
    if not circulant or kernel != "flint":
        return False, False, 0
    return False, True, DENSE_BELOW.get(n, 0)
