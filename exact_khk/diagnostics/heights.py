"""Height growth of an exact orbit, fitted as linear, quadratic or exponential in the step.

The height h_k of the orbit point x_k = Φ^k(x_0) is the bit length of its
largest numerator or denominator (:func:`~exact_khk.arith.point_height`).
Heights follow degrees: h_k ≲ d_k·(h_0 + c), so integrable maps (polynomial
degree growth) have polynomially growing heights and a non-integrable map
such as the Kahan Lotka–Volterra map has heights that roughly double per
step.  Unlike the degree fit (:mod:`.recurrence`), this one is *heuristic*: the
models h ≈ a + b k, h ≈ a + b k + c k² (least squares) and log h ≈ α + β k
(least squares, rate r = e^β) are compared by their relative RMS error on
the last two thirds of the steps (the asymptotic regime); the simplest polynomial model within 1.5× the best error and under
5 % is chosen, otherwise the exponential model if it is the best.

An orbit whose height passes ``max_bits`` is cut there (an exponential orbit
cannot be followed for long).

>>> from exact_khk.systems.expressions import ExpressionSystem
>>> lv = ExpressionSystem.from_expressions(["u", "v"], field=["u - u*v", "u*v - v"])
>>> g = height_growth(lv.field("f"), ["1/2", "1/3"], "1/10", steps=14)
>>> g.growth, g.rate > 1.6
('exponential', True)
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from exact_khk.arith import get_arith, point_height
from exact_khk.errors import InputError
from exact_khk.parsing import any_int_digits, check_count, parse_rational

MODELS = ("linear", "quadratic", "exponential")


def lstsq(xs, ys, degree):
    """Least-squares polynomial coefficients (lowest first) of the given degree
    (normal equations in floats; tiny systems).

    >>> [round(c, 6) for c in lstsq([0, 1, 2, 3], [1, 3, 5, 7], 1)]
    [1.0, 2.0]
    """
    n = degree + 1
    A = [[sum(x ** (i + j) for x in xs) for j in range(n)] for i in range(n)]
    b = [sum(y * x ** i for x, y in zip(xs, ys)) for i in range(n)]
    for c in range(n):  # Gaussian elimination with partial pivoting
        piv = max(range(c, n), key=lambda r: abs(A[r][c]))
        A[c], A[piv], b[c], b[piv] = A[piv], A[c], b[piv], b[c]
        if A[c][c] == 0:
            return [0.0] * n
        for r in range(c + 1, n):
            f = A[r][c] / A[c][c]
            A[r] = [a - f * p for a, p in zip(A[r], A[c])]
            b[r] -= f * b[c]
    out = [0.0] * n
    for r in range(n - 1, -1, -1):
        out[r] = (b[r] - sum(A[r][j] * out[j] for j in range(r + 1, n))) / A[r][r]
    return out


def _poly(coeffs, x):
    return sum(c * x ** i for i, c in enumerate(coeffs))


@dataclass(frozen=True)
class HeightGrowth:
    """Heights h_0..h_K (bits) of an exact orbit and the fitted growth model.

    ``growth`` is 'linear', 'quadratic', 'exponential' or 'undetermined';
    ``models`` maps each model to (parameters, relative RMS error); ``rate`` is
    e^β of the exponential model."""

    heights: tuple
    growth: str
    models: dict
    rate: float
    truncated: bool

    def curve(self, model, k):
        """The fitted value of ``model`` at step k (for plots)."""
        params = self.models[model][0]
        return math.exp(params[0] + params[1] * k) if model == "exponential" else _poly(params, k)

    @any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
    def to_json(self) -> dict:
        return {"heights": list(self.heights), "growth": self.growth, "rate": self.rate,
                "truncated": self.truncated,
                "models": {m: {"parameters": list(p), "relative_rms": e} for m, (p, e) in self.models.items()}}

    @any_int_digits()
    def summary(self) -> str:
        cut = " (cut at the bit limit)" if self.truncated else ""
        tail = ", ".join(map(str, self.heights[-4:]))
        what = f"exponential, about x{self.rate:.3g} per step" if self.growth == "exponential" else self.growth
        return (f"heights (bits) of the exact orbit, {len(self.heights) - 1} steps{cut}: ..., {tail}; "
                f"growth {what} (heuristic least-squares fit)")


def classify_heights(heights, truncated=False) -> HeightGrowth:
    """Fit the three models to h_1..h_K and choose (module docstring)."""
    hs = [int(h) for h in heights]
    if len(hs) < 5:
        raise InputError(f"steps: at least 4 steps are needed to fit a height growth, got {len(hs) - 1}")
    start = max(1, (len(hs) - 1) // 3)  # asymptotic growth: skip the first third (transients)
    ks = list(range(start, len(hs)))
    ys = [max(h, 1) for h in hs[start:]]
    models = {}
    for name, deg in (("linear", 1), ("quadratic", 2)):
        c = lstsq(ks, ys, deg)
        models[name] = (tuple(c), _rel_rms(ys, [_poly(c, k) for k in ks]))
    ab = lstsq(ks, [math.log(y) for y in ys], 1)
    models["exponential"] = (tuple(ab), _rel_rms(ys, [math.exp(ab[0] + ab[1] * k) for k in ks]))
    best = min(e for _, e in models.values())
    growth = "undetermined"
    for name in ("linear", "quadratic"):
        if models[name][1] <= max(1.5 * best, 1e-9) and models[name][1] < 0.05:
            growth = name
            break
    else:
        if models["exponential"][1] == best and ab[1] > 0.05:
            growth = "exponential"
    return HeightGrowth(tuple(hs), growth, models, math.exp(ab[1]), truncated)


def _rel_rms(ys, fs):
    return math.sqrt(sum(((y - f) / y) ** 2 for y, f in zip(ys, fs)) / len(ys))


@any_int_digits()
def height_growth(field, x0, eps, steps=30, max_bits=200_000, arith="flint") -> HeightGrowth:
    """Heights of the exact orbit of ``x0`` under the Kahan map of ``field`` (a
    QuadraticField) at step size ``eps``, and their fitted growth."""
    from exact_khk.kahan.map import KahanMap

    if isinstance(steps, bool) or not isinstance(steps, int) or not 4 <= steps <= 100_000:
        raise InputError(f"steps: expected an integer in [4, 100000] for the height fit, got {steps!r}")
    if x0 is None:
        raise InputError("x0: a starting point is needed for the height growth")
    check_count(max_bits, "max_bits", 1, 10 ** 9)
    ar = get_arith(arith)
    if not ar.rational:  # heights are bits of exact rationals
        raise InputError(f"arith: height growth needs an exact rational arithmetic (flint, gmpy2, fraction), "
                         f"got {ar.name}")
    phi = KahanMap(field, parse_rational(eps, "eps"), ar)
    x = phi.point(x0, "x0")
    hs, truncated = [point_height(ar, x)], False
    for _ in range(steps):
        x = phi.step(x)
        hs.append(point_height(ar, x))
        if hs[-1] > max_bits:
            truncated = True
            break
    if truncated and len(hs) < 5:
        raise InputError(f"max_bits: the orbit passed {max_bits} bits after {len(hs) - 1} steps (x0 has {hs[0]} "
                         f"bits); at least 4 steps are needed to fit a height growth: raise max_bits, start "
                         f"from a lower point, or leave the heights out")
    return classify_heights(hs, truncated)


def plot_growth(path, degrees=None, heights=None, title=""):
    """Write an image (PNG, PDF or SVG by the suffix, atomically): degree against step and log2(height) against step, with the
    fitted curves and the classification in the legends (needs matplotlib)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("plot: matplotlib is not installed (pip install matplotlib)") from None
    panels = [p for p in (degrees, heights) if p is not None]
    if not panels:
        raise InputError("plot: nothing to plot")
    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 5.2),
                             squeeze=False)
    axes = axes[0]
    i = 0
    if degrees is not None:
        ax, fit = axes[i], degrees.fit
        ds = list(degrees.degrees)
        m = min(fit.fitted_on, len(ds))
        label = fit.growth if fit.growth != "polynomial" else f"polynomial, degree {fit.polynomial_degree}"
        if fit.dynamical_degree is not None:
            label += f"; λ ∈ [{fit.dynamical_degree.enclosure[0][:8]}, {fit.dynamical_degree.enclosure[1][:8]}]"
        ax.plot(range(len(ds)), ds, "-", color="0.75", lw=1, zorder=1)
        ax.plot(range(m), ds[:m], "o", ms=4, color="C0", label=f"d_k, fitted ({m} terms)", zorder=3)
        ax.plot(range(m, len(ds)), ds[m:], "o", ms=5, mfc="none", color="C1",
                label=f"d_k, confirming the fit ({len(ds) - m} terms)", zorder=3)
        if fit.growth == "exponential":
            ax.set_yscale("log")
        ax.set_xlabel("step k")
        ax.set_ylabel("degree d_k of Φ^k" + (" (log scale)" if fit.growth == "exponential" else ""))
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0, -0.16), frameon=False,  # below: off the data
                  title=f"χ = {fit.characteristic_text()}: {label}", title_fontsize=8)
        ax.margins(x=0.04, y=0.12)
        i += 1
    if heights is not None:
        ax = axes[i]
        ks = list(range(len(heights.heights)))
        hs = [max(h, 1) for h in heights.heights]
        ax.semilogy(ks, hs, "o", ms=4, color="C0", label="height of x_k (bits)", zorder=3)
        # only the chosen model is drawn: a rejected polynomial fit can dip below zero, where the log
        # axis shows it as broken fragments; the rejected models' errors are named in the legend
        if heights.growth in MODELS:
            curve = [heights.curve(heights.growth, k) for k in ks[1:]]
            ax.semilogy(ks[1:], [v if v > 0 else float("nan") for v in curve], "-", color="C3", lw=2,
                        label=f"{heights.growth} fit, rel. error {heights.models[heights.growth][1]:.2g}")
        rejected = [f"{m} {heights.models[m][1]:.2g}" for m in MODELS if m != heights.growth and m in heights.models]
        if rejected:
            ax.plot([], [], " ", label="rejected fits (not drawn), rel. error: " + ", ".join(rejected))
        ax.set_ylim(min(hs) / 1.5, max(hs) * 1.5)   # the data's range, not a diverging fit's
        ax.set_xlabel("step k")
        ax.set_ylabel("height of x_k (bits, log scale)")
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(0, -0.16), frameon=False,  # below: off the data
                  title=f"height growth: {heights.growth} (heuristic fit)", title_fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    from exact_khk.studies.output import write_atomic

    write_atomic(path, lambda fh: fig.savefig(fh, format=plot_format(path), dpi=110), "--plot")
    plt.close(fig)
    return path


#: the image formats :func:`plot_growth` writes, by the file's suffix
PLOT_FORMATS = ("png", "pdf", "svg")


def plot_format(path, what: str = "--plot") -> str:
    """The image format of ``path`` from its suffix (checked before any work: InputError
    naming the option ``what`` unless one of :data:`PLOT_FORMATS`)."""
    suffix = os.path.splitext(str(path))[1].lower().lstrip(".")
    if suffix not in PLOT_FORMATS:
        raise InputError(f"{what}: {str(path)!r}: expected a file name ending in "
                         f"{', '.join('.' + f for f in PLOT_FORMATS)}")
    return suffix
