"""The Lie–Poisson family of Petrera & Suris, in the conventions of docs/conventions.md.

Phase space Q^{2n}, x = (u, v) with u = x[0:n], v = x[n:2n] (0-based).

* cyclic Hankel matrix ``X(w)[i][j] = w[(i+j) % n]``;
* Lie–Poisson tensor ``J(x) = [[0, X(u)], [-X(u), 0]]``;
* cyclic shift ``P[i][(i+1) % n] = 1`` and ``A = P ⊕ P``;
* admissible Hessian ``Hs = [[X(a), X(b)], [X(b), X(c)]]``, ``H0 = xᵀ Hs x / 2``;
* commuting Hamiltonians ``H_i`` with Hessian ``A^i Hs``;
* vector field ``f(x) = J(x) M x`` for a Hessian ``M``: ``M = Hs`` (the field f),
  ``M = B Hs`` (associated field g for an involution B), ``M = A Hs``
  (non-associated control; ``(2I + A) Hs`` for n = 2, where A is itself an
  involution).

Involutions are named by sign patterns ``s = (s_0, ..., s_{n-1})``: ``s_j`` is
the eigenvalue of B on the ω^j-eigenspace of P (ω = e^{2πi/n}); as a string,
``'-++'`` is B_0 for n = 3.

>>> sys3 = LiePoissonSystem.from_vectors("1,0,2", "0,1,0", "3,1,1")
>>> sys3.n
3
>>> [str(v) for v in involution_circulant(3, "-++")]
['1/3', '-2/3', '-2/3']
>>> involution_circulant(4, "+-++")
Traceback (most recent call last):
...
exact_khk.errors.NotRationalError: signs '+-++' split the class {j : gcd(j, 4) = 1} = {1, 3} (signs -, +): this involution is not rational; it needs cyclotomic arithmetic
"""

from __future__ import annotations

import dataclasses
import random
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import lru_cache
from math import gcd, lcm

from exact_khk.linalg.numtheory import ramanujan_sum
from exact_khk.errors import InputError, NotRationalError
from exact_khk.parsing import MAX_N, _short, check_count, format_signs, parse_signs, parse_vector
from exact_khk.systems.base import System
from exact_khk.systems.quadratic import QuadraticField, certainly_zero

# --- small exact matrix helpers (Fractions, lists of rows) ------------------


def hankel(w):
    """Cyclic Hankel matrix X(w)[i][j] = w[(i+j) mod n]."""
    n = len(w)
    return [[w[(i + j) % n] for j in range(n)] for i in range(n)]


def circulant_power_matrix(coeffs):
    """Σ_k coeffs[k] P^k as an n×n matrix, P[i][(i+1) % n] = 1."""
    n = len(coeffs)
    return [[coeffs[(j - i) % n] for j in range(n)] for i in range(n)]


def block_diag2(M):
    """M ⊕ M."""
    n = len(M)
    Z = [Fraction(0)] * n
    return [list(r) + Z for r in M] + [Z + list(r) for r in M]


def mat_mul(A, B):
    """A·B; for rational entries by FLINT (``fmpq_mat``: the dense Hessians of g and of
    the control at n = 16 are 30 products of 32×32 matrices, 9 s as Fraction sums, 13 %
    of ``certify --n 16``), else as sums (e.g. entries in Q(ω))."""
    if all(type(t) in (Fraction, int) for M in (A, B) for r in M for t in r):
        from exact_khk.linalg.flintmat import mat

        return [[Fraction(int(q.p), int(q.q)) for q in r] for r in (mat(A) * mat(B)).table()]
    cols = list(zip(*B))
    return [[sum((a * b for a, b in zip(r, c)), Fraction(0)) for c in cols] for r in A]


def mat_add(A, B, alpha=1, beta=1):
    return [[alpha * a + beta * b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def eye(N):
    return [[Fraction(int(i == j)) for j in range(N)] for i in range(N)]


# --- involutions by sign pattern ------------------------------------------


def divisor_classes(n: int) -> dict[int, list[int]]:
    """{d: [j : gcd(j, n) = d]} for the divisors d of n (j = 0 is in class n)."""
    classes: dict[int, list[int]] = {}
    for j in range(n):
        classes.setdefault(gcd(j, n), []).append(j)
    return dict(sorted(classes.items()))


#: the most sign patterns :func:`rational_sign_patterns` lists (2^{#divisors of n}; n = 720720
#: would have 2^240)
MAX_SIGN_PATTERNS = 2 ** 16


def rational_sign_patterns(n: int) -> list[str]:
    """All sign patterns whose involution has rational entries (2^{#divisors})."""
    check_count(n, "n", 2, MAX_N)
    classes = list(divisor_classes(n).values())
    if 2 ** len(classes) > MAX_SIGN_PATTERNS:
        raise InputError(f"n = {n}: {len(classes)} divisors give 2^{len(classes)} rational sign patterns, "
                         f"beyond the limit of {MAX_SIGN_PATTERNS} (MAX_SIGN_PATTERNS)")
    out = []
    for mask in range(2 ** len(classes)):
        s = [0] * n
        for bit, cls in enumerate(classes):
            for j in cls:
                s[j] = -1 if (mask >> bit) & 1 else 1
        out.append(format_signs(s))
    return sorted(out)


def involution_circulant(n: int, signs) -> tuple[Fraction, ...]:
    """Coefficients α_k of B = Σ_k α_k P^k for a rational sign pattern.

    α_k = (1/n) Σ_j s_j ω^{-jk} = (1/n) Σ_{d|n} s_d c_{n/d}(k) (Ramanujan sums);
    raises :class:`NotRationalError` if ``signs`` is not constant on the classes
    {j : gcd(j, n) = d}.  α_k depends on k only through gcd(k, n), so the cost
    is O(n) gcds (plus a sum over pairs of divisors), not n Ramanujan sums per
    divisor: 5 ms for B_0 at n = 20 000.

    >>> involution_circulant(6, "-+++++") == tuple(Fraction(int(k == 0)) - Fraction(2, 6) for k in range(6))
    True
    """
    return _involution_circulant(n, format_signs(parse_signs(signs, n)))


@lru_cache(maxsize=32)
def _involution_circulant(n: int, signs: str) -> tuple[Fraction, ...]:
    s = parse_signs(signs, n)
    classes = divisor_classes(n)
    sign_of = {}
    for d, cls in classes.items():
        vals = {s[j] for j in cls}
        if len(vals) > 1:
            shown = ", ".join(format_signs([s[j]]) for j in cls)
            raise NotRationalError(
                f"signs {format_signs(s)!r} split the class {{j : gcd(j, {n}) = {d}}} = "
                f"{{{', '.join(map(str, cls))}}} (signs {shown}): this involution is not rational; "
                f"it needs cyclotomic arithmetic")
        sign_of[d] = vals.pop()
    # α_k = (1/n) Σ_d s_d c_{n/d}(k), and c_q(k) = c_q(gcd(k, n)) for q | n: one value per divisor g = gcd(k, n)
    by_gcd = {g: Fraction(sum(sd * ramanujan_sum(n // d, g) for d, sd in sign_of.items()), n) for g in classes}
    return tuple(by_gcd[g] for g in map(gcd, range(n), [n] * n))


def nontrivial_sign_patterns(n: int) -> list[str]:
    """All 2^n − 2 sign patterns of involutions B ≠ ±I (rational or not)."""
    out = [format_signs([1 - 2 * ((m >> j) & 1) for j in range(n)]) for m in range(2 ** n)]
    return sorted(p for p in out if p not in ("+" * n, "-" * n))


def is_rational_pattern(n: int, signs) -> bool:
    """True when the involution of ``signs`` has rational entries."""
    s = parse_signs(signs, n)
    return all(len({s[j] for j in cls}) == 1 for cls in divisor_classes(n).values())


def involution_circulant_cyclotomic(n: int, signs) -> tuple:
    """Coefficients α_k = (1/n) Σ_j s_j ω^{-jk} of B = Σ_k α_k P^k in Q(ω), ω = ζ_n,
    for *every* sign pattern, as :class:`~exact_khk.arith.cyclotomic.CycloNumber` (any
    ``cyclo:N`` with n | N, or ``gf:P`` with P ≡ 1 mod n, converts them).

    >>> [str(t) for t in involution_circulant_cyclotomic(3, "+-+")]
    ['1/3', '2/3 + 2/3*z', '-2/3*z']
    >>> involution_circulant_cyclotomic(3, "-++") == involution_circulant(3, "-++")
    True
    """
    from exact_khk.arith.cyclotomic import cyclotomic_field

    s = parse_signs(signs, n)
    K = cyclotomic_field(n)
    return tuple(sum((s[j] * K.zeta_power(-j * k) for j in range(n)), K.zero) / n
                 for k in range(n))


def expresses_omega(ar, n: int) -> bool:
    """Whether ``ar`` can hold the entries of the non-rational involutions of size n.

    Those entries lie in Q(ω), ω = ζ_n, and the pattern with s_1 = −1 alone has the entry
    −(2/n)·ω^{−1} at k = 1, so this is whether ``ar`` holds ω: one conversion, where
    building that involution costs n² operations in Q(ω) (minutes at n = 5 000).

    >>> from exact_khk import get_arith
    >>> [expresses_omega(get_arith(a), 6) for a in ("flint", "cyclo:12", "cyclo:8", "gf:13", "gf:11")]
    [False, True, False, True, False]
    """
    from exact_khk.arith.cyclotomic import cyclotomic_field

    try:
        ar.convert(cyclotomic_field(n).gen)
    except (TypeError, ValueError, ArithmeticError):  # InputError is a ValueError
        return False
    return True


def default_involutions(n: int, arith=None) -> list:
    """The involutions certified by default: every rational one except ±I (for n = 2:
    '+-' = A and '-+' = −A) or, when ``arith`` contains ω = e^{2πi/n} (``cyclo:N`` with
    n | N, ``gf:P`` with P ≡ 1 mod n), every one except ±I."""
    if arith is not None and n >= 3:
        from exact_khk.arith import get_arith

        if expresses_omega(get_arith(arith), n):
            return nontrivial_sign_patterns(n)
    return sorted(s for s in rational_sign_patterns(n) if s not in ("+" * n, "-" * n))


def check_signs_arith(n: int, signs, ar, option: str = "signs"):
    """InputError unless ``ar`` holds the involution of every pattern of ``signs``: rational
    patterns anywhere, the others only where ω = e^(2πi/n) is (:func:`expresses_omega`)."""
    irrational = next((s for s in signs if not is_rational_pattern(n, s)), None)
    if irrational is not None and not expresses_omega(ar, n):
        raise InputError(f"{option}: {format_signs(parse_signs(irrational, n))!r} is not a rational involution; "
                         f"it needs an arithmetic containing omega = e^(2 pi i/{n}), e.g. --arith cyclo:{n}")


# --- the system -------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class LiePoissonSystem(System):
    """A member of the family, given by its admissible Hessian blocks a, b, c ∈ Q^n.

    As a :class:`~exact_khk.systems.base.System` it knows its fields (``'f'``,
    the associated ``'g[signs]'``, the non-associated ``'control'``), its
    integrals H̃ and K̃ (:mod:`~exact_khk.systems.lie_poisson.invariants`) and its
    invariant Poisson tensor Π; the paper's certificate
    (:mod:`exact_khk.certification.lie_poisson`) checks all of them.
    """

    kind = "lie-poisson"

    a: tuple
    b: tuple
    c: tuple
    _fields: dict = field(default_factory=dict, repr=False, compare=False)
    #: the involutions of the associated fields (None: :func:`default_involutions`), see :meth:`with_involutions`
    chosen: tuple = field(default=None, repr=False, compare=False)
    #: the involutions of the integrals K~[s] (None: those of the fields), see :meth:`with_involutions`
    chosen_integrals: tuple = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        n = len(self.a)
        if n < 2:
            raise InputError(f"n: the family needs n >= 2, got n = {n}")
        for name in ("a", "b", "c"):
            object.__setattr__(self, name, parse_vector(getattr(self, name), name, length=n))

    @classmethod
    def from_vectors(cls, a, b, c):
        """From three vectors (strings like ``'1/2,-3,0'`` or sequences of rationals)."""
        a, b, c = parse_vector(a, "a"), parse_vector(b, "b"), parse_vector(c, "c")
        if not len(a) == len(b) == len(c):
            raise InputError(f"a, b, c need one length n: a has {len(a)} entries, b {len(b)}, c {len(c)}")
        if len(a) < 2:
            raise InputError(f"n: the family needs n >= 2, got n = {len(a)}")
        return cls(a, b, c)

    @classmethod
    def random(cls, n: int, seed: int, bound: int = 3):
        """Small random integer Hessian blocks in [-bound, bound], reproducible from ``seed``."""
        if not isinstance(n, int) or isinstance(n, bool) or n < 2:
            raise InputError(f"n: the family needs n >= 2, got {n!r}")
        if n > MAX_N:
            raise InputError(f"n: {_short(n)} is beyond the limit of {MAX_N:,} (MAX_N)")
        _check_seed_bound(seed, bound)
        rng = random.Random(seed)
        draw = lambda: tuple(Fraction(rng.randint(-bound, bound)) for _ in range(n))  # noqa: E731
        return cls(draw(), draw(), draw())

    @property
    def n(self) -> int:
        return len(self.a)

    @property
    def dim(self) -> int:
        return 2 * self.n

    @property
    def name(self) -> str:
        return f"lie-poisson n={self.n}"

    @property
    def variables(self) -> tuple:
        return tuple(f"u{i}" for i in range(self.n)) + tuple(f"v{i}" for i in range(self.n))

    default_x0 = property(lambda self: DEFAULT_X0 if self.n == 3 else random_point(self.n, 0))

    def describe(self) -> str:
        fmt = lambda v: "(" + ", ".join(str(t) for t in v) + ")"  # noqa: E731
        return f"Lie–Poisson system n={self.n}: a={fmt(self.a)}, b={fmt(self.b)}, c={fmt(self.c)}"

    def to_json(self) -> dict:
        return {"family": "lie-poisson", "n": self.n, "a": [str(t) for t in self.a],
                "b": [str(t) for t in self.b], "c": [str(t) for t in self.c]}

    @classmethod
    def from_json(cls, d: dict) -> "LiePoissonSystem":
        """From :meth:`to_json` (InputError naming the key if malformed)."""
        unknown = sorted(set(d) - {"family", "n", "a", "b", "c"})
        if unknown:
            raise InputError(f"system: unknown key(s) {', '.join(map(repr, unknown))} for the Lie–Poisson family")
        for key in ("a", "b", "c"):
            if key in d and not isinstance(d[key], list):
                raise InputError(f"system.{key}: expected a list of rationals (strings), got "
                                 f"{'a string' if isinstance(d[key], str) else type(d[key]).__name__}")
        try:
            system = cls.from_vectors(d["a"], d["b"], d["c"])
        except (KeyError, TypeError):
            raise InputError("system: a Lie–Poisson system needs the vectors 'a', 'b', 'c'") from None
        if "n" in d and (type(d["n"]) is not int or d["n"] != system.n):
            raise InputError(f"system.n: {d['n']!r} does not match the length {system.n} of the vectors a, b, c")
        return system

    @classmethod
    def from_spec(cls, d: dict) -> "LiePoissonSystem":
        """From a sweep's system spec: ``{"default": True}`` or ``{"n": n, "seed": s, "bound": b}``."""
        if d.get("default"):
            return default_system()
        return cls.random(d["n"], d["seed"], d.get("bound", 3))

    # what the family knows, as the System interface asks it ---------------------
    #: the options of the family's own certificate (the paper's theorems), beyond System's
    certificate_options = ("signs", "poisson_points", "identities", "prove")
    #: the command-line option that sets the dimension 2n
    size_option = "--n"

    def coordinate_names(self) -> tuple:
        return tuple(f"x{i}" for i in range(self.dim))

    @property
    def short_name(self) -> str:
        return f"n = {self.n}"

    def involutions(self, arith=None) -> list:
        """The involutions certified (:meth:`with_involutions`; default :func:`default_involutions`)."""
        return list(self.chosen) if self.chosen is not None else default_involutions(self.n, arith)

    def with_involutions(self, signs, integrals=None) -> "LiePoissonSystem":
        """The same system whose fields, integrals and claims are those of the involutions ``signs``
        (patterns as :func:`~exact_khk.parsing.format_signs` writes them; non-rational ones over Q(ω));
        ``integrals``: the involutions of the integrals K~[s] instead (the identity: H~ alone)."""
        return dataclasses.replace(self, chosen=tuple(signs),
                                   chosen_integrals=None if integrals is None else tuple(integrals))

    def integral_involutions(self) -> list:
        """The involutions s of the integrals K~[s] (:meth:`with_involutions`)."""
        chosen = self.involutions() if self.chosen_integrals is None else self.chosen_integrals
        return [s for s in chosen if s != "+" * self.n]

    def field_names(self) -> tuple:
        """f and the associated g[s] of every involution of :meth:`involutions`."""
        return ("f",) + tuple(f"g[{s}]" for s in self.involutions())

    def integrals(self) -> dict:
        """H̃ (of f) and K̃[s] (H̃ of g[s]) for every field of :meth:`field_names`."""
        from exact_khk.systems.lie_poisson.invariants import HtildeIntegral

        out = {"H~": HtildeIntegral("H~", self.field("f"), "x^T (I - eps^2 (Hs J(x))^2)^-1 Hs x")}
        for s in self.integral_involutions():
            out[f"K~[{s}]"] = HtildeIntegral(f"K~[{s}]", self.field("g", s, cyclotomic=True),
                                             f"as H~ with B Hs, B = B[{s}]", base="H~", signs=s)
        return out

    #: the paper's certificate (:mod:`exact_khk.certification.claims`): its claims in the paper's order, about
    #: every map along its orbit, with the family's controls (:meth:`negative_controls`) for the automatic ones
    claim_order = ("definition", "integrals", "commutation", "reversibility", "poisson", "involution", "rank")
    claims_on_every_orbit = own_controls_only = True

    def fast_forms(self, ar, eps):
        """The closed forms of :class:`~.flint_forms.FlintForms` (python-flint matrices, the same
        rationals as the generic route) when ``ar`` is the ``flint`` arithmetic, else None."""
        from exact_khk.linalg.flintmat import uses_flint

        if not uses_flint(ar):
            return None
        from exact_khk.systems.lie_poisson.flint_forms import FlintForms

        return FlintForms(self, eps)

    def gradient_ranks(self, ar) -> list:
        """The ranks claimed of gradients of the integrals, as (name, statement, rows, rank):
        ``rows(grad)`` the rows at a point from ``grad(name)``, the gradient of an integral there.
        All of :meth:`integrals` span the dimension of the span of I and the involutions (the
        rank of their sign vectors); the n integrals H̃_i of A^i Hs, ∇H̃_i = A^i ∇H̃, rank n."""
        from exact_khk.linalg.flintmat import rank
        from exact_khk.systems.lie_poisson.invariants import shift_index

        n, names = self.n, list(self.integrals())
        r = rank([[1] * n] + [list(parse_signs(s, n)) for s in self.integral_involutions()])
        n_rational = len(divisor_classes(n))
        over = (f"all n = {n} integrals are expressible in {ar.name}" if expresses_omega(ar, n) or n_rational == n
                else f"over Q only {n_rational} of the n = {n} integrals are expressible (the others need Q(omega))")
        return [(f"rank of integral gradients ({', '.join(names)})",
                 f"the gradients of the {len(names)} integrals expressible here have rank {r} "
                 f"(the dimension of their span: functional independence, proved by one orbit point of full rank; "
                 f"the rank may drop at critical points) on the Phi_f orbit; {over}",
                 lambda grad: [grad(name) for name in names], r),
                ("rank of integral gradients A^i grad H~ (i < n)",
                 f"the gradients A^i grad H~ (i = 0..{n - 1}) of the n integrals H~_i have full rank n = {n} "
                 f"(functional independence, proved by one orbit point of full rank) on the Phi_f orbit",
                 lambda grad: [[grad("H~")[s] for s in shift_index(n, i)] for i in range(n)], n)]

    def tracked(self) -> tuple:
        """(integrals, commuting fields) a study follows along an orbit: H̃, and K̃ and g of
        B_0 only (:meth:`integrals` has one K̃ per involution: 2^d - 2 of them for d divisors of n)."""
        from exact_khk.systems.lie_poisson.invariants import HtildeIntegral

        f, g = self.field("f"), self.field("g", signs=b0_signs(self.n))
        return ({"H~": HtildeIntegral("H~", f, "x^T (I - eps^2 (M J(x))^2)^-1 M x, M = Hs"),
                 "K~": HtildeIntegral("K~", g, f"as H~ with M = B_0 Hs, B_0 = {g.signs}")}, {g.label: g})

    def poisson(self):
        """Π = J − ε² J Hs J Hs J (the paper's invariant Poisson tensor)."""
        from exact_khk.systems.lie_poisson.invariants import PiTensor

        return PiTensor(self)

    def negative_controls(self, x0, eps) -> list:
        """The four controls of the paper's certificate (:func:`~.controls.negative_controls`)."""
        from exact_khk.systems.lie_poisson.controls import negative_controls

        return negative_controls(self, x0, eps)

    def singular_J(self, x) -> bool:
        """Whether J(x) is singular (:func:`hankel_singular` of u)."""
        return hankel_singular(list(x)[:self.n])

    def random_point(self, seed: int, bound: int = 3, eps=None) -> tuple:
        """A point off the degenerate sets of every map the certificate steps (:func:`random_point`)."""
        return random_point(self.n, seed, bound, system=self, eps=eps)

    def seeded_point(self, seed: int, eps=None, skip: int = 0) -> tuple:
        return random_point(self.n, seed, system=self, eps=eps, skip=skip)

    # matrices ------------------------------------------------------------
    @property
    def hessian(self):
        """Hs = [[X(a), X(b)], [X(b), X(c)]]."""
        Xa, Xb, Xc = hankel(self.a), hankel(self.b), hankel(self.c)
        return [ra + rb for ra, rb in zip(Xa, Xb)] + [rb + rc for rb, rc in zip(Xb, Xc)]

    @property
    def shift(self):
        """A = P ⊕ P with P[i][(i+1) % n] = 1."""
        e1 = [Fraction(0)] * self.n
        e1[1 % self.n] += 1
        return block_diag2(circulant_power_matrix(e1))

    def J(self, x):
        """Lie–Poisson tensor J(x) = [[0, X(u)], [-X(u), 0]] (entries from x)."""
        n = self.n
        if len(x) != 2 * n:
            raise InputError(f"x: expected {2 * n} coordinates, got {len(x)}")
        zero = x[0] * 0
        Xu = hankel(list(x[:n]))
        return ([[zero] * n + list(r) for r in Xu] + [[-t for t in r] + [zero] * n for r in Xu])

    def hamiltonian_hessian(self, i: int = 0):
        """Hessian A^i Hs of the commuting Hamiltonian H_i."""
        M = self.hessian
        for _ in range(i % self.n):
            M = self._times(self.shift, M)
        return M

    def _times(self, C, M):
        """C·M for a rational matrix C and the Hessian-like M (a hook: ball entries for
        :class:`~.real.RealLiePoissonSystem`)."""
        return mat_mul(C, M)

    def _structure(self, kind, signs=None, power=0):
        """The field's circulant structure from a, b, c (a hook: none for ball entries)."""
        return structure_from_system(self, kind, signs, power)

    def involution(self, signs, cyclotomic: bool = False):
        """B = Bc ⊕ Bc for a rational sign pattern (see :func:`involution_circulant`);
        with ``cyclotomic=True`` any pattern, non-rational ones with entries in Q(ω)
        (see :func:`involution_circulant_cyclotomic`)."""
        if cyclotomic and not is_rational_pattern(self.n, signs):
            alpha = involution_circulant_cyclotomic(self.n, signs)
        else:
            alpha = involution_circulant(self.n, signs)
        return block_diag2(circulant_power_matrix(alpha))

    def hamiltonian(self, ar, x, i: int = 0):
        """H_i(x) = xᵀ A^i Hs x / 2, evaluated in arithmetic ``ar``."""
        M = self.hamiltonian_hessian(i)
        s = ar.zero
        for r in range(self.dim):
            for cidx in range(self.dim):
                if not certainly_zero(M[r][cidx]):
                    s = s + ar.convert(M[r][cidx]) * x[r] * x[cidx]
        return s / ar.convert(2)

    # fields --------------------------------------------------------------
    def named_field(self, name="f", cyclotomic=False) -> "LiePoissonField":
        """The field called ``name`` (:meth:`System.named_field`): ``'f'``, ``'control'``,
        ``'g'`` or its alias ``'b0'`` (g for B_0 = '-+…+'), and ``'g[SIGNS]'`` or the
        bare pattern ``'SIGNS'`` (g for that involution).  ``cyclotomic``: build a g of a
        non-rational pattern over Q(ω) (see :meth:`field`) — a bool, or a function
        returning one, called only when a pattern is named (deciding whether an
        arithmetic holds ω costs O(n²)).

        >>> s = default_system()
        >>> [s.named_field(t).label for t in ("f", "g", "b0", "+--", "g[+--]", "control")]
        ['f', 'g[-++]', 'g[-++]', 'g[+--]', 'g[+--]', 'control']
        >>> s.named_field("g[")
        Traceback (most recent call last):
        ...
        exact_khk.errors.InputError: field: expected f, g, b0, g[SIGNS], a sign pattern SIGNS or control \
for the Lie–Poisson family, got 'g['
        """
        if not isinstance(name, str) or name in ("f", "g", "control"):
            return super().named_field(name)  # the type check, or the field of that name
        if name == "b0":
            return self.field("g")
        if name.startswith("g[") and name.endswith("]"):
            signs = name[2:-1]
        elif name and set(name) <= set("+-"):
            signs = name
        else:
            raise InputError(f"field: expected f, g, b0, g[SIGNS], a sign pattern SIGNS or control "
                             f"for the Lie–Poisson family, got {name!r}")
        parse_signs(signs, self.n)  # a bad pattern is refused before ω is asked for
        return self.field("g", signs=signs, cyclotomic=cyclotomic() if callable(cyclotomic) else cyclotomic)

    def field_for_signs(self, signs) -> "LiePoissonField":
        """f for the identity pattern '+…+', else the associated g[signs] (over Q(ω)
        when the involution is not rational)."""
        if signs == "+" * self.n:
            return self.field("f")
        return self.field("g", signs, cyclotomic=True)

    def field_from_hessian(self, M, label="f", structure=None) -> "LiePoissonField":
        """The field f(x) = J(x) M x for any 2n×2n matrix M (no admissibility check).

        ``M`` may be a :class:`LazyHessian` (built on first use) and ``structure``
        the field's :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure`, known
        from a, b, c: the structured step then never builds the (2n)² matrix."""
        N = self.dim
        if isinstance(M, LazyHessian):
            if len(M) != N:
                raise InputError(f"hessian: expected a {N}x{N} matrix")
            rows = M
        else:
            if len(M) != N or any(len(r) != N for r in M):
                raise InputError(f"hessian: expected a {N}x{N} matrix")
            rows = tuple(tuple(r) for r in M)
        # The quadratic terms are built on first use (LiePoissonField.terms):
        # the structured step never needs them, and for large n they are huge.
        fld = LiePoissonField(N, None, tuple(() for _ in range(N)), tuple(0 for _ in range(N)), label,
                              system=self, hessian=rows)
        if structure is not None:
            fld._cache["circulant"] = structure
        return fld

    def field(self, kind: str = "f", signs=None, power: int = 0,
              cyclotomic: bool = False) -> "LiePoissonField":
        """A named field: ``'f'`` (Hessian A^power Hs), ``'g'`` (B Hs for the
        involution with sign pattern ``signs``, default B_0 = '-+…+'), or
        ``'control'`` (A Hs for n >= 3, (2I + A) Hs for n = 2).

        A non-rational pattern raises :class:`NotRationalError` unless
        ``cyclotomic=True``: then the field's coefficients lie in Q(ω) and it is
        usable in ``cyclo:N`` (n | N) and ``gf:P`` (P ≡ 1 mod n) only."""
        if signs is None and isinstance(kind, str) and kind.startswith("g[") and kind.endswith("]"):
            kind, signs = "g", kind[2:-1]  # the name of field_names()
        if isinstance(power, bool) or not hasattr(power, "__index__"):
            raise InputError(f"power: expected an integer (the power of the shift A), got {power!r}")
        power = int(power)
        if abs(power) > 2 ** 63:  # A^n = I: a power is only named by its size here
            raise InputError(f"power: expected an integer of at most 2^63 in size (A^n = I), got {_short(power)}")
        cyc = bool(cyclotomic) and kind == "g" and signs is not None \
            and not is_rational_pattern(self.n, signs)
        key = (kind, None if signs is None else format_signs(parse_signs(signs, self.n)), power, cyc)
        if key in self._fields:
            return self._fields[key]
        if kind == "f":
            fld = self._declared_field(lambda: self.hamiltonian_hessian(power), "f" if power == 0 else f"f_{power}",
                                       self._structure("f", power=power))
        elif kind == "g":
            s = format_signs(parse_signs(signs if signs is not None else b0_signs(self.n), self.n))
            if cyc:
                fld = self.field_from_hessian(mat_mul(self.involution(s, cyclotomic=True), self.hessian),
                                              f"g[{s}]")
            else:
                involution_circulant(self.n, s)  # a non-rational pattern raises here, at once
                fld = self._declared_field(lambda: self._times(self.involution(s), self.hessian), f"g[{s}]",
                                           self._structure("g", s))
            object.__setattr__(fld, "signs", s)
        elif kind == "control":
            C = (lambda: self.shift) if self.n >= 3 else (lambda: mat_add(eye(self.dim), self.shift, 2, 1))
            fld = self._declared_field(lambda: self._times(C(), self.hessian), "control", self._structure("control"))
        else:
            raise InputError(f"field: unknown kind {kind!r}; expected 'f', 'g' or 'control'")
        self._fields[key] = fld
        return fld

    def _declared_field(self, hessian, label, structure):
        """The field of the Hessian ``hessian()`` (built on first use) with the circulant
        structure the system declares for it: a :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure`,
        or None for none (then it is not looked for in the Hessian either)."""
        fld = self.field_from_hessian(LazyHessian(self.dim, hessian), label)
        fld._cache["circulant"] = structure
        return fld


# The built-in default system (used by ``exact-khk certify`` with no arguments):
# n = 3, a = (1, 0, 2), b = (0, 1, 0), c = (3, 1, 1); x0 = (1, 2, -1, 1/2, 0, 1);
# eps = 1/10.  Chosen as small integers with every block nonzero; its orbits are
# regular (no singular step) for at least 200 steps, as the tests check.
DEFAULT_VECTORS = ("1,0,2", "0,1,0", "3,1,1")
DEFAULT_X0 = ("1", "2", "-1", "1/2", "0", "1")
DEFAULT_EPS = Fraction(1, 10)


def default_system() -> "LiePoissonSystem":
    """The built-in default system (n = 3); see ``DEFAULT_VECTORS``."""
    return LiePoissonSystem.from_vectors(*DEFAULT_VECTORS)


def hankel_singular(u) -> bool:
    """Whether X(u) (and so J(x) for x = (u, v)) is singular, for rational u.

    X(u) is singular iff a DFT value û_j = Σ_i u_i ω^{ij} (ω = e^{2πi/n}) vanishes,
    iff gcd(Σ_i u_i t^i, tⁿ − 1) ≠ 1 (one polynomial gcd, fast for any n).  The
    set is invariant under every Kahan map of the family (each {û_j = 0} is an
    invariant linear subspace of the fields); it contains u = 0, u with equal
    coordinates, the hyperplane Σu = 0 and, for even n, Σ(−1)^i u_i = 0.

    >>> hankel_singular([1, 1, 1]), hankel_singular([1, -1, 0]), hankel_singular([1, 2, 0])
    (True, True, False)
    """
    import flint

    qs = [Fraction(t) for t in u]
    n = len(qs)
    den = 1
    for q in qs:
        den = den * q.denominator // gcd(den, q.denominator)
    p = flint.fmpz_poly([int(q * den) for q in qs])
    if p == 0:
        return True
    return p.gcd(flint.fmpz_poly([-1] + [0] * (n - 1) + [1])).degree() > 0


#: largest n for which :func:`random_point` also tests a given system and ε
#: (equilibrium, pole of H̃, singular first step: dense exact work, O(n³))
RANDOM_POINT_SYSTEM_CHECK_MAX_N = 16
#: draws before :func:`random_point` gives up the system-dependent conditions
_MAX_DRAWS = 200


def _check_seed_bound(seed, bound):
    """InputError unless ``seed`` is an int (or None) and ``bound`` a positive int."""
    if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)):
        raise InputError(f"seed: expected an integer, got {seed!r}")
    check_count(bound, "bound", 1, 2 ** 63)


def random_point(n: int, seed: int, bound: int = 3, system=None, eps=None, skip: int = 0) -> tuple:
    """A reproducible small-integer point of Q^{2n}, off the known degenerate sets.

    Points are drawn from one random stream per ``seed`` (integers in
    [-bound, bound]); a draw is rejected, and the next one taken, when

    * X(u) is singular (:func:`hankel_singular`: u = 0, equal coordinates,
      Σu = 0, an alternating sum 0 for even n, …) — an invariant set where
      J(x) is singular, h(x, x̃) is undefined and negative controls cannot fail;

    and, when a ``system`` (and ``eps``, default :data:`DEFAULT_EPS`) is given and
    n ≤ :data:`RANDOM_POINT_SYSTEM_CHECK_MAX_N`, when

    * x is an equilibrium (Hs x = 0: every map of the family fixes it);
    * H̃(x, ε) has a pole, or the first step of a map a certificate steps from x
      is singular: Φ_f, Φ_g[s] of every rational involution s of
      :meth:`LiePoissonSystem.involutions` and the control map;
    * the first step of one of these maps has X(u) singular (x on its critical set,
      which the map sends into the invariant singular set, where its inverse and
      the other maps' steps are undefined: the commutation Φ_f∘Φ_g = Φ_g∘Φ_f
      steps Φ_f at Φ_g(x)).

    The system-dependent rules only reject draws of the same stream: a first draw off
    the singular sets that passes them is the point drawn without a system.  After 200 draws the system-dependent rules
    are dropped (a system whose every small point is degenerate, e.g. Hs = 0).  ``skip``: the
    accepted draws to pass over (``certify --seed`` redraws when a later step is singular).
    """
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise InputError(f"n: expected a positive integer, got {n!r}")
    _check_seed_bound(seed, bound)
    check_system = system is not None and n <= RANDOM_POINT_SYSTEM_CHECK_MAX_N
    rng = random.Random(f"x0-{seed}")
    draws = 0
    while True:
        x = tuple(Fraction(rng.randint(-bound, bound)) for _ in range(2 * n))
        if not any(x) or hankel_singular(x[:n]):
            continue
        draws += 1
        if not check_system or draws > _MAX_DRAWS or not _degenerate_for(system, x, eps):
            if not skip:
                return x
            skip -= 1


def _degenerate_for(system, x, eps) -> bool:
    """The system-dependent rejection rules of :func:`random_point`."""
    from exact_khk.arith import get_arith, to_element
    from exact_khk.errors import PoleError, SingularMatrix
    from exact_khk.systems.lie_poisson import circulant
    from exact_khk.linalg.dense import solve
    from exact_khk.systems.lie_poisson.invariants import Htilde

    eps = DEFAULT_EPS if eps is None else eps
    if not any(sum((h * t for h, t in zip(row, x)), Fraction(0)) for row in system.hessian):
        return True
    ar, N = get_arith("fraction"), 2 * system.n
    e = to_element(ar, eps, "eps")

    def first_step(fld):
        """Φ(x) of a homogeneous field: (I − ε f'(x)) y = x, by the 2×2 solve over circulants
        where the blocks are circulant (at n = 14 the whole check took 155 ms with the dense
        Fraction solve, 4 ms with this one: docs/benchmarks.md)."""
        st = fld.circulant_structure()
        if st is not None:
            return circulant.exact_step(st, x, e, ar)
        J = fld.jacobian(ar, x)
        Y, _ = solve(ar, [[(i == j) - e * J[i][j] for j in range(N)] for i in range(N)], [[t] for t in x])
        return [row[0] for row in Y]

    try:
        Htilde(system.field("f"), x, eps, ar)
        for name in system.field_names() + ("control",):  # every map a certificate steps from x
            if hankel_singular(first_step(system.field(name))[:system.n]):
                return True
    except (PoleError, SingularMatrix):
        return True
    return False


def b0_signs(n: int) -> str:
    """The sign pattern of B_0 = I - (2/n)(𝟙 ⊕ 𝟙): '-' then n-1 '+'."""
    check_count(n, "n", 1, 2 ** 63)
    return "-" + "+" * (n - 1)


class LazyHessian(Sequence):
    """The rows of a 2n×2n Hessian, built by ``build()`` on first access to an entry.

    The named fields of a :class:`LiePoissonSystem` know their circulant
    structure from a, b, c in O(n) to O(n log n); their (2n)² matrix (and its
    O((2n)³) product with an involution) is built only when a dense path needs
    it, so that ``exact-khk orbit --n 20000`` on the structured path stays O(n)
    in memory."""

    def __init__(self, dim, build):
        self._dim, self._build, self._rows = dim, build, None

    def _get(self):
        if self._rows is None:
            self._rows = tuple(tuple(r) for r in self._build())
        return self._rows

    def __len__(self):
        return self._dim

    def __getitem__(self, i):
        return self._get()[i]

    def __iter__(self):
        return iter(self._get())

    def __eq__(self, other):
        return tuple(self) == tuple(other)

    def __repr__(self):
        return f"LazyHessian({self._dim}x{self._dim}, {'built' if self._rows is not None else 'not built'})"


@dataclass(frozen=True, eq=False)
class LiePoissonField(QuadraticField):
    """f(x) = J(x) M x for a system's tensor J and a constant matrix M (the Hessian)."""

    system: LiePoissonSystem = None
    hessian: tuple = ()
    signs: str | None = None

    def circulant_structure(self, cyclotomic=False):
        """The circulant structure of the step's blocks (Hessian blocks cyclic Hankel), or
        None; ``cyclotomic``: entries in Q(ω) count too (the associated fields of
        non-rational involutions)."""
        from exact_khk.systems.lie_poisson.circulant import circulant_structure

        return circulant_structure(self, cyclotomic)

    def structured_steps(self, ar, method, eps):
        """The family's fast steps for a Kahan map (:func:`~exact_khk.systems.lie_poisson.steps.circulant_steps`:
        the split and structured steps where the blocks are circulant), or None (dense)."""
        from exact_khk.systems.lie_poisson.steps import circulant_steps

        return circulant_steps(self, ar, method, eps)

    def integer_tensor_rows(self, p, q):
        """``(V, R)`` of :meth:`integer_system`: from the declared circulant structure when there
        is one (:func:`~exact_khk.systems.lie_poisson.circulant.structure_rows`, O(n²) integer
        work, one common factor apart: the same solutions) instead of the O(n³) rational
        Jacobian."""
        st = self.circulant_structure()
        if st is None:
            return self.integer_rows(p, q)
        from exact_khk.systems.lie_poisson.circulant import structure_rows

        first, R = structure_rows(st, p, q)
        n, N = st.n, self.dim  # entry (bi·n + i, bj·n + j) is the first row's entry (j − i) mod n
        return [first[i // n][j // n][(j % n - i % n) % n] for i in range(N) for j in range(N)], R

    def terms(self) -> tuple:
        """The quadratic terms of f(x) = J(x) M x, built once on first use:
        f_i = Σ_{k<n} x_k (J(e_k) M x)_i with (J(e_k) M)[i][l] = M[n + (k-i)%n][l]
        for i < n and −M[(k-i')%n][l] for i = n + i'."""
        hit = self._cache.get("terms")
        if hit is None:
            n, N, M = self.system.n, self.dim, self.hessian
            out = []
            for i in range(N):
                row, sign = (n + 0, 1) if i < n else (0, -1)
                ii = i if i < n else i - n
                acc = {}
                for k in range(n):
                    Mr = M[row + (k - ii) % n]
                    for l in range(N):
                        c = Mr[l]
                        if not certainly_zero(c):  # a ball that contains 0 is kept
                            key = (min(k, l), max(k, l))
                            acc[key] = acc.get(key, 0) + sign * c
                out.append(tuple((key, c) for key, c in sorted(acc.items()) if not certainly_zero(c)))
            hit = self._cache["terms"] = tuple(out)
        return hit


def _correlate(coeffs, w):
    """(Σ_k c_k w_{(j+k) mod n})_j by one python-flint integer polynomial product: the
    coefficient of t^j in (Σ_i w_i t^i)(Σ_k c_k t^{(−k) mod n}) mod tⁿ − 1, with
    the denominators of w and c cleared first (O(n log n), no Fraction arithmetic)."""
    import flint

    n = len(w)
    w = [Fraction(t) for t in w]
    c = [Fraction(coeffs[-k % n]) for k in range(n)]
    dw, dc = lcm(*(t.denominator for t in w)), lcm(*(t.denominator for t in c))
    W = flint.fmpz_poly([t.numerator * (dw // t.denominator) for t in w])
    C = flint.fmpz_poly([t.numerator * (dc // t.denominator) for t in c])
    prod = W * C
    if prod.degree() >= n:
        prod = prod.truncate(n) + prod.right_shift(n)
    vals = [int(t) for t in prod.coeffs()] + [0] * (n - prod.degree() - 1)
    den = dw * dc
    return tuple(Fraction(v, den) for v in vals)


def structure_from_system(system, kind="f", signs=None, power=0):
    """The :class:`~exact_khk.systems.lie_poisson.circulant.CirculantStructure` of ``system.field(kind,
    signs, power)`` computed from the vectors a, b, c alone: O(n) for f and the control
    field, O(n log n) for g (one polynomial product per block for n > 64), where the
    dense Hessian would cost O(n²) memory and its product with B O(n³) time.

    First rows: A^p X(w) = X(w shifted by p); B X(w) = X(Σ_k α_k w shifted by k).
    """
    n = system.n

    def left(coeffs, w):  # first row of (Σ_k coeffs[k] P^k) X(w): Σ_k c_k w_{j+k}
        nonzero = [(k, c) for k, c in enumerate(coeffs) if c]
        if len(nonzero) == 1 and nonzero[0][1] == 1:  # a shift: A^p X(w) = X(w shifted by p)
            k = nonzero[0][0]
            return tuple(w[k:]) + tuple(w[:k])
        if len(nonzero) <= 4 or n <= 64:
            return tuple(sum((c * w[(j + k) % n] for k, c in nonzero), Fraction(0)) for j in range(n))
        return _correlate(coeffs, w)

    unit = lambda k: [Fraction(int(i == k % n)) for i in range(n)]  # noqa: E731
    if kind == "f":
        coeffs = unit(power)
    elif kind == "g":
        coeffs = involution_circulant(n, signs if signs is not None else b0_signs(n))
    elif kind == "control":
        coeffs = unit(1) if n >= 3 else [2 * a + b for a, b in zip(unit(0), unit(1))]
    else:
        raise InputError(f"field: unknown kind {kind!r}; expected 'f', 'g' or 'control'")
    a, b, c = system.a, system.b, system.c
    from exact_khk.systems.lie_poisson.circulant import CirculantStructure

    return CirculantStructure(n, ((left(coeffs, a), left(coeffs, b)), (left(coeffs, b), left(coeffs, c))))
