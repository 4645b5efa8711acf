"""Catalogue families: systems with a size or a parameter, named ``NAME:K=V[,K=V]``.

A family is a generator: a function of integer parameters that returns the table of a
system file (the dict ``tomllib`` would read, ``[literature]`` included), which is then read
by the same reader as every ``*.toml`` file of the catalogue.  Each family lists its
parameters with their allowed ranges and the members ``exact-khk systems`` shows; any other
member in range is built on request (``volterra-periodic:N=7``).  Parameters are integers
(a system name has no '/'), so rational choices are made inside the generator.
"""

from __future__ import annotations

from ...errors import InputError

#: largest chain length: every step solves a dense N x N system, and the tests certify chains
MAX_CHAIN = 40


def _vars(N):
    return [f"x{i}" for i in range(1, N + 1)]


def _chain_x0(N):
    """A small positive point with unequal coordinates (a constant point is often an equilibrium)."""
    return [f"{i + 2}/{2 * i + 1}" for i in range(N)]


def _volterra(N, periodic):
    xs = _vars(N)
    at = (lambda k: xs[k % N]) if periodic else (lambda k: xs[k] if 0 <= k < N else None)
    field = {}
    for k in range(N):
        right, left = at(k + 1), at(k - 1)
        terms = [t for t in (right, f"-{left}" if left else None) if t]
        field[xs[k]] = f"{xs[k]}*({' + '.join(terms).replace('+ -', '- ')})" if terms else "0"
    kind = "periodic" if periodic else "open (Kac-van Moerbeke, x0 = x{N+1} = 0)"
    eq = "x_k' = x_k (x_{k+1} - x_{k-1}), indices mod N" if periodic else \
        "x_k' = x_k (x_{k+1} - x_{k-1}), x_0 = x_{N+1} = 0"
    return {
        "title": f"Volterra chain, {kind}, N = {N}",
        "source": f"Volterra lattice {eq}. The sum of the x_k is a linear integral of the ODE (the terms "
                  "telescope), hence of every Kahan map (Kahan's method is a Runge-Kutta method, CMOQ "
                  "arXiv:1209.1164, and Runge-Kutta methods keep linear integrals).",
        "variables": xs, "field": field,
        "integrals": {"sum": " + ".join(xs)},
        "controls": {"sum_of_squares": " + ".join(f"{x}**2" for x in xs)},
        "defaults": {"x0": _chain_x0(N), "eps": "1/10"},
        "literature": {
            "reference": "Kouloukas, Quispel, Vanhaecke, arXiv:1601.05006 "
                         "(introduction: the open chain (1.1) is the Kac-van Moerbeke system)",
            "integrable": "unknown", "integrals": "unknown",
            "notes": "No statement on the integrability of the Kahan map of this chain was found in the texts "
                     "read (the openings of arXiv:1008.1040, 1405.3740, 1601.05006; the abstract of Evripidou, "
                     "Kassotakis, Vanhaecke arXiv:2105.05799 says the Kahan map of a connected skew-symmetric "
                     "Lotka-Volterra graph is a Poisson map for the quadratic structure exactly for clonings of "
                     "the graph i -> j for i < j, the KQV system: a statement on the Poisson property, not on "
                     "integrability); only the linear integral sum(x_k), kept by every Kahan map, is declared. "
                     "The atlas's exponential degrees for N = 5, d_k = (4^(k+1) - 1)/3, were recomputed for "
                     "k = 1..4 (5, 21, 85, 341; periodic and open chain) by SymPy alone over a rational line "
                     "(scripts/check_volterra_degrees.py)."}}


def _kqv(N):
    xs = _vars(N)
    field = {}
    for i in range(N):
        plus, minus = xs[i + 1:], xs[:i]
        inner = " + ".join(plus) + "".join(f" - {x}" for x in minus)
        inner = inner.lstrip(" +") if plus else "-" + " - ".join(minus)
        field[xs[i]] = f"{xs[i]}*({inner})"
    poisson = [["0" if i == j else (f"{xs[i]}*{xs[j]}" if i < j else f"-{xs[i]}*{xs[j]}") for j in range(N)]
               for i in range(N)]
    return {
        "title": f"Generalized Lotka-Volterra chain of Kouloukas-Quispel-Vanhaecke, N = {N}",
        "source": "T. E. Kouloukas, G. R. W. Quispel, P. Vanhaecke, 'Liouville integrability and "
                  "superintegrability of a generalized Lotka-Volterra system and its Kahan discretization', "
                  "arXiv:1601.05006, system (1.2): x_i' = x_i (sum_{j>i} x_j - "
                  "sum_{j<i} x_j). Hamiltonian H = sum x_j for the quadratic bracket {x_i, x_j} = x_i x_j "
                  "(i < j); H is linear, so every Kahan map keeps it.",
        "variables": xs, "field": field,
        "integrals": {"H": " + ".join(xs)},
        "poisson": {"matrix": poisson},
        "controls": {"sum_of_squares": " + ".join(f"{x}**2" for x in xs)},
        "defaults": {"x0": _chain_x0(N), "eps": "1/10"},
        "literature": {
            "reference": "Kouloukas-Quispel-Vanhaecke arXiv:1601.05006 (abstract); Evripidou, Kassotakis, "
                         "Vanhaecke arXiv:2105.05799 (abstract)",
            "integrable": "yes", "integrals": "unknown",
            "poisson": "{x_i, x_j} = x_i x_j for i < j (the Lotka-Volterra bracket) is preserved: "
                       "arXiv:2105.05799 (the graph with an arc i -> j iff i < j, all values equal, has the "
                       "Kahan-Poisson property)",
            "notes": "The abstract of 1601.05006 states Liouville and superintegrability of the Kahan "
                     "discretization; the integrals themselves were not read, so only the linear H is declared."}}


def _henon_heiles(sigma):
    B = 16 if sigma == -16 else 1
    H = f"(p1**2 + p2**2)/2 + (q1**2 + {B}*q2**2)/2 + q1**2*q2 - ({sigma})*q2**3/3"
    case = {-1: "separable", -6: "KdV", -16: "Sawada-Kotera (frequencies 1:4)"}.get(sigma)
    return {
        "title": f"Henon-Heiles, sigma = {sigma}" + (f" ({case} integrable case)" if case else
                                                      " (non-integrable ODE)" if sigma == 1 else ""),
        "source": "H = (p1^2 + p2^2)/2 + (q1^2 + B q2^2)/2 + q1^2 q2 - (sigma/3) q2^3 as a first-order "
                  "quadratic system in (q1, q2, p1, p2) with the canonical K; B = 16 for sigma = -16, else 1. "
                  "sigma = 1 is Henon and Heiles' system (Astron. J. 69 (1964) 73); the ODE is integrable "
                  "for sigma = -1 (B = 1), -6 and -16 (B = 16) (Bountis, Segur, Vivaldi, Phys. Rev. A 25 "
                  "(1982) 1257; Chang, Tabor, Weiss, J. Math. Phys. 23 (1982) 531). CMOQ (arXiv:1209.1164): "
                  "with K constant and H cubic the Kahan map keeps H + (2 eps/3) grad H^T (I - eps f')^{-1} f "
                  "and dx/det(I - eps f') (our h = 2 eps), certified by the 'cmoq' claim.",
        "variables": ["q1", "q2", "p1", "p2"],
        "hamiltonian": {"K": [["0", "0", "1", "0"], ["0", "0", "0", "1"], ["-1", "0", "0", "0"],
                              ["0", "-1", "0", "0"]], "H": H},
        "controls": {"H": H},
        "defaults": {"x0": ["1/5", "-1/10", "1/4", "1/5"], "eps": "1/10"},
        "literature": {
            "reference": "Celledoni, McLachlan, Owren, Quispel, arXiv:1209.1164 (abstract)",
            "integrable": "unknown", "integrals": 1,
            "measure": "dx/det(I - eps f'(x)) (CMOQ, constant K, cubic H)",
            "notes": "CMOQ give one integral (the modified energy) and a measure for every sigma; whether the "
                     "Kahan map has a second integral in the integrable cases of the ODE is not stated in "
                     "what we read (abstracts of 1209.1164 and 1405.3740)."}}


def _planar_cubic(g1, g2, g3):
    # l1 = x, l2 = y, l3 = x + y (any three distinct lines through 0 are linearly equivalent to these,
    # and Kahan's method commutes with linear maps); J = [[0, 1], [-1, 0]].  With H = l1^g1 l2^g2 l3^g3,
    # l1^(1-g1) l2^(1-g2) l3^(1-g3) J grad H = sum_i g_i (prod_{j != i} l_j) J grad l_i: quadratic for every g.
    fx = f"{g2}*x*(x + y) + {g3}*x*y"
    fy = f"-{g1}*y*(x + y) - {g3}*x*y"
    H = f"x**{g1}*y**{g2}*(x + y)**{g3}"
    table = {
        "title": f"Planar cubic class, gamma = ({g1}, {g2}, {g3})",
        "source": "x' = l1^(1-g1) l2^(1-g2) l3^(1-g3) J grad H, H = l1^g1 l2^g2 l3^g3, with l1 = x, l2 = y, "
                  "l3 = x + y, J = [[0, 1], [-1, 0]]: x' = g2 x(x+y) + g3 xy, y' = -g1 y(x+y) - g3 xy "
                  "(quadratic for every gamma). R. Zander, 'On the singularity structure of Kahan "
                  "discretizations of a class of quadratic vector fields', arXiv:2003.01659; CMOQ "
                  "arXiv:1209.1164 and arXiv:1405.3740.",
        "variables": ["x", "y"],
        "field": {"x": fx, "y": fy},
        "controls": {"H": H} if g1 + g2 + g3 <= 12 else {},
        "defaults": {"x0": ["1/3", "1/2"], "eps": "1/10"},
        "literature": {
            "reference": "Zander arXiv:2003.01659, Theorem 1.1 (as summarised on its abstract page)",
            "integrable": "unknown", "integrals": "unknown",
            "notes": "Zander's Theorem 1.1: degrees grow exponentially (non-integrable) except for a list of "
                     "gamma, up to permutation and scaling; that list was not in the text we read."}}
    if (g1, g2, g3) == (1, 1, 1):   # J grad H with H cubic and J constant: CMOQ's setting
        table["hamiltonian"] = {"K": [["0", "1"], ["-1", "0"]], "H": "x**2*y + x*y**2"}
        table["literature"].update({
            "reference": "Celledoni, McLachlan, Owren, Quispel arXiv:1209.1164 (abstract); Petrera, Smirin, "
                         "Suris arXiv:1810.09928 (abstract)",
            "integrable": "yes", "integrals": 1, "measure": "dx/det(I - eps f'(x)) (CMOQ)",
            "notes": "gamma = (1,1,1) is f = J grad H with H = xy(x + y) cubic: CMOQ's modified energy and "
                     "measure (certified by the 'cmoq' claim); planar quadratic Hamiltonian fields have "
                     "integrable Kahan maps (1810.09928)."})
    return table


def _zhukovsky_volterra(beta1, beta2, beta3):
    n = sum(b != 0 for b in (beta1, beta2, beta3))
    found = {}
    if beta2 == beta3 == 0:
        # derived here (not from a paper): the Euler-top integral H31 with x1 shifted by b1/a3; found by
        # solving for the numerator with the Euler-top denominator fixed, checked by SymPy in the tests
        found["I31"] = "(a3*(x1 - b1/a3)**2 - a1*x3**2)/(1 - eps**2*a1*a3*x2**2)"
    return {
        "title": f"Zhukovsky-Volterra gyrostat, beta = ({beta1}, {beta2}, {beta3})",
        "source": "x1' = a1 x2 x3 + b3 x2 - b2 x3 (cyclic), i.e. x' = x cross (A x + beta) with A = diag(0, 1, 3), "
                  "a = (A3 - A2, A1 - A3, A2 - A1) = (2, -3, 1); continuous integrals |x|^2 and "
                  "<A x, x> + 2<beta, x>. Petrera, Pfadler, Suris arXiv:1008.1040 (section on the "
                  "Zhukovsky-Volterra gyrostat).",
        "variables": ["x1", "x2", "x3"],
        "parameters": {"a1": "2", "a2": "-3", "a3": "1", "b1": str(beta1), "b2": str(beta2), "b3": str(beta3)},
        "field": {"x1": "a1*x2*x3 + b3*x2 - b2*x3", "x2": "a2*x3*x1 + b1*x3 - b3*x1",
                  "x3": "a3*x1*x2 + b2*x1 - b1*x2"},
        "integrals": found,
        "controls": {"C": "x1**2 + x2**2 + x3**2", "H": "x2**2 + 3*x3**2 + 2*(b1*x1 + b2*x2 + b3*x3)"},
        "defaults": {"x0": ["1", "1/2", "-1/3"], "eps": "1/10"},
        "literature": {
            "reference": "Petrera, Pfadler, Suris arXiv:1008.1040",
            "integrable": "unknown", "integrals": "unknown",
            "notes": f"{n} nonzero component(s) of beta. The overview 1008.1040 treats this system; its "
                     "statements and integrals for each case were not in the text we could read (its "
                     "opening only), so nothing is claimed. " + (
                         "Alonso, Suris, Wei arXiv:2207.06051 (abstract) give a novel integrable Kahan-type "
                         "discretization of the gyrostat with two nonzero components: a different map, so it "
                         "states nothing on this one. " if n == 2 else "") + (
                         "I31 is our own: with beta = (b1, 0, 0), (a3 (x1 - b1/a3)^2 - a1 x3^2)/(1 - eps^2 a1 a3 "
                         "x2^2) is an integral (found by a linear solve with the Euler-top denominator, checked "
                         "with SymPy for b1 = 1, 3, -5/2 and two eps); a second one was not found in the time "
                         "available." if found else "No integral is declared.")}}


def _kirchhoff(b1, b3):
    return {
        "title": f"Kirchhoff case of the rigid body in an ideal fluid, B = diag({b1}, {b1}, {b3})",
        "source": "H = <m, A m>/2 + <m, B p> + <p, C p>/2 with A = diag(1, 1, 2), B = diag(b1, b1, b3), "
                  "C = diag(1, 1, 3): m' = m x dH/dm + p x dH/dp, p' = p x dH/dm. For B = b I the terms of B "
                  "cancel (m x b p + p x b m = 0) and the field equals that of B = 0. m3 is a linear integral "
                  "(A, B, C axially symmetric), kept by every Kahan map. Petrera, Pfadler, Suris "
                  "arXiv:1008.1040 (Kirchhoff case).",
        "variables": ["m1", "m2", "m3", "p1", "p2", "p3"],
        "parameters": {"a1": "1", "a3": "2", "b1": str(b1), "b3": str(b3), "c1": "1", "c3": "3"},
        # m x (A m + B p) + p x (B m + C p), p x (A m + B p)
        "field": {"m1": "m2*(a3*m3 + b3*p3) - m3*(a1*m2 + b1*p2) + p2*(b3*m3 + c3*p3) - p3*(b1*m2 + c1*p2)",
                  "m2": "m3*(a1*m1 + b1*p1) - m1*(a3*m3 + b3*p3) + p3*(b1*m1 + c1*p1) - p1*(b3*m3 + c3*p3)",
                  "m3": "m1*(a1*m2 + b1*p2) - m2*(a1*m1 + b1*p1) + p1*(b1*m2 + c1*p2) - p2*(b1*m1 + c1*p1)",
                  "p1": "p2*(a3*m3 + b3*p3) - p3*(a1*m2 + b1*p2)",
                  "p2": "p3*(a1*m1 + b1*p1) - p1*(a3*m3 + b3*p3)",
                  "p3": "p1*(a1*m2 + b1*p2) - p2*(a1*m1 + b1*p1)"},
        "integrals": {"m3": "m3"},
        "controls": {"p_squared": "p1**2 + p2**2 + p3**2", "mp": "m1*p1 + m2*p2 + m3*p3",
                     "H": "(a1*(m1**2 + m2**2) + a3*m3**2)/2 + b1*(m1*p1 + m2*p2) + b3*m3*p3 + "
                          "(c1*(p1**2 + p2**2) + c3*p3**2)/2"},
        "defaults": {"x0": ["1", "-1", "1/2", "1/3", "1", "-1/2"], "eps": "1/10"},
        "literature": {
            "reference": "Petrera, Pfadler, Suris arXiv:1008.1040",
            "integrable": "unknown", "integrals": "unknown",
            "notes": "The overview 1008.1040 treats the Kirchhoff case; its statements for B = 0, B ~ I and "
                     "b3 != b1 were not in the text we could read, so only the linear integral m3 (kept by "
                     "every Kahan map) is declared."}}


#: family name -> (generator, {parameter: (lowest, highest)}, listed members, one-line description);
#: every parameter pattern is listed at a second point too (fixed small values, chosen before any run:
#: docs/atlas.md classifies both), so that a verdict is seen at more than one parameter point
FAMILIES = {
    "volterra-periodic": (lambda N: _volterra(N, True), {"N": (3, MAX_CHAIN)}, [{"N": 5}, {"N": 4}],
                          "periodic Volterra chain of length N"),
    "volterra-open": (lambda N: _volterra(N, False), {"N": (2, MAX_CHAIN)}, [{"N": 5}, {"N": 4}],
                      "open Volterra (Kac-van Moerbeke) chain of length N"),
    "kqv-lotka-volterra": (_kqv, {"N": (2, MAX_CHAIN)}, [{"N": 5}, {"N": 4}],
                           "Kouloukas-Quispel-Vanhaecke generalized Lotka-Volterra chain of length N"),
    "henon-heiles": (_henon_heiles, {"sigma": (-100, 100)},
                     [{"sigma": -1}, {"sigma": -6}, {"sigma": -16}, {"sigma": 1}, {"sigma": 2}],
                     "Henon-Heiles with cubic coefficient sigma (integrable ODE for -1, -6, -16)"),
    "planar-cubic": (_planar_cubic, {"g1": (1, 6), "g2": (1, 6), "g3": (1, 6)},
                     [{"g1": 1, "g2": 1, "g3": 1}, {"g1": 1, "g2": 1, "g3": 2}, {"g1": 1, "g2": 2, "g3": 3},
                      {"g1": 1, "g2": 2, "g3": 4}],
                     "planar cubic class l1^(1-g1) l2^(1-g2) l3^(1-g3) J grad(l1^g1 l2^g2 l3^g3)"),
    "zhukovsky-volterra": (_zhukovsky_volterra, {"beta1": (-9, 9), "beta2": (-9, 9), "beta3": (-9, 9)},
                           [{"beta1": 1, "beta2": 0, "beta3": 0}, {"beta1": 1, "beta2": 2, "beta3": 0},
                            {"beta1": 1, "beta2": -1, "beta3": 2},
                            {"beta1": 0, "beta2": 0, "beta3": 3}, {"beta1": 2, "beta2": -3, "beta3": 0},
                            {"beta1": 2, "beta2": 1, "beta3": -3}],
                           "Zhukovsky-Volterra gyrostat with gyrostatic momentum beta"),
    "kirchhoff": (_kirchhoff, {"b1": (-9, 9), "b3": (-9, 9)},
                  [{"b1": 0, "b3": 0}, {"b1": 1, "b3": 1}, {"b1": 1, "b3": 2}, {"b1": 2, "b3": -1}],
                  "Kirchhoff case, B = diag(b1, b1, b3)"),
}


def member_name(family: str, params: dict) -> str:
    """The canonical name ``family:K=V,...`` (parameters in the family's order)."""
    return family + ":" + ",".join(f"{k}={params[k]}" for k in FAMILIES[family][1])


def listed() -> list:
    """The canonical names of the listed members of every family."""
    return [member_name(f, p) for f, (_, _, members, _) in FAMILIES.items() for p in members]


def describe_parameters(family: str) -> str:
    """``N = 3..40`` and the like."""
    return ", ".join(f"{k} = {lo}..{hi}" for k, (lo, hi) in FAMILIES[family][1].items())


def parse(spec: str):
    """(family, {parameter: int}) from ``NAME:K=V[,K=V]``; InputError naming the allowed ranges."""
    family, _, rest = spec.partition(":")
    if family not in FAMILIES:
        raise InputError(f"unknown catalogue family {family!r}; families: {', '.join(FAMILIES)}")
    ranges = FAMILIES[family][1]
    allowed = f"{family} takes {describe_parameters(family)} (integers), e.g. {listed_example(family)}"
    params = {}
    for item in filter(None, rest.split(",")):
        key, eq, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not eq or key not in ranges:
            raise InputError(f"{spec!r}: {item!r} is not a parameter K=V of the family; {allowed}")
        if key in params:
            raise InputError(f"{spec!r}: {key} is given twice; {allowed}")
        try:
            n = int(value)
        except ValueError:
            raise InputError(f"{spec!r}: {key}={value!r} is not an integer; {allowed}") from None
        lo, hi = ranges[key]
        if not lo <= n <= hi:
            raise InputError(f"{spec!r}: {key}={n} is outside {lo}..{hi}; {allowed}")
        params[key] = n
    missing = [k for k in ranges if k not in params]
    if missing:
        raise InputError(f"{spec!r}: missing {', '.join(missing)}; {allowed}")
    return family, params


def listed_example(family: str) -> str:
    return member_name(family, FAMILIES[family][2][0])


def table(family: str, params: dict) -> dict:
    """The system-file table of one member (its name is the canonical member name)."""
    t = FAMILIES[family][0](**params)
    return dict(t, format=1, name=member_name(family, params))
