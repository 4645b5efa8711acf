"""2n×2n integer matrices made of four n×n blocks that are circulant or cyclic Hankel,
multiplied as polynomials in Z[t]/(tⁿ − 1) (python-flint ``fmpz_poly``).

A circulant C(c)[i][j] = c_{(j−i) mod n} and a cyclic Hankel block
X(w)[i][j] = w_{(i+j) mod n} are stored as the polynomials c(t) = Σ c_k t^k and
w(t) = Σ w_k t^k (0-based, docs/conventions.md).  With c̄(t) = c(t^{-1}) (the
reflection) and products taken mod tⁿ − 1:

    C(a) C(b) = C(a b)      C(a) X(w) = X(ā w)      X(w) C(a) = X(w a)
    X(w) X(z) = C(w̄ z)      C(c)ᵀ = C(c̄)            X(w)ᵀ = X(w)

(the circulants and the Hankel blocks together are the group ring of the
dihedral group).  The Jacobian blocks of the Kahan maps of the Lie–Poisson
family are circulant, J(x) and the Hessians have Hankel blocks, so the
Poisson-map identity dΦ Π dΦᵀ = Π∘Φ multiplied out is a few such products: n-term
polynomial products instead of (2n)³ scalar products.  A sum of a circulant and a
Hankel block has no such form: :class:`Mixed` is raised, and callers use dense
matrices instead.

>>> J = BlockMatrix.hankel_blocks(3, [[None, [1, 2, 0]], [[-1, -2, 0], None]])
>>> (J * J.T()).dense() == J.dense() * J.dense().transpose()
True
"""

from __future__ import annotations

import flint

fmpz_poly, fmpz_mat = flint.fmpz_poly, flint.fmpz_mat


class Mixed(ValueError):
    """A block would be the sum of a circulant and a Hankel block."""


def _reduce(p, n):
    """p mod tⁿ − 1."""
    while p.degree() >= n:
        p = p.truncate(n) + p.right_shift(n)
    return p


def _reflect(p, n):
    """p(t^{-1}) mod tⁿ − 1."""
    return fmpz_poly([p[(-k) % n] for k in range(n)])


class BlockMatrix:
    """[[B00, B01], [B10, B11]], each block ``None`` (zero) or ``(kind, poly)`` with kind
    ``'C'`` (circulant) or ``'X'`` (cyclic Hankel) and poly an ``fmpz_poly`` of degree < n."""

    __slots__ = ("n", "b")

    def __init__(self, n, blocks):
        self.n, self.b = n, blocks

    @classmethod
    def hankel_blocks(cls, n, rows):
        """From first rows (lists of n integers, or None for a zero block) of Hankel blocks."""
        return cls(n, [[None if w is None else ("X", fmpz_poly(list(w))) for w in r] for r in rows])

    @classmethod
    def circulant_blocks(cls, n, polys):
        """From coefficient lists c (C[i][j] = c[(j − i) mod n]) or None."""
        return cls(n, [[None if c is None else ("C", fmpz_poly(list(c))) for c in r] for r in polys])

    @classmethod
    def identity(cls, n):
        return cls.circulant_blocks(n, [[[1], None], [None, [1]]])

    # -- blockwise arithmetic ------------------------------------------------------
    def _blk_mul(self, x, y):
        if x is None or y is None:
            return None
        (kx, p), (ky, q), n = x, y, self.n
        if kx == "C":
            return ("C", _reduce(p * q, n)) if ky == "C" else ("X", _reduce(_reflect(p, n) * q, n))
        return ("X", _reduce(p * q, n)) if ky == "C" else ("C", _reduce(_reflect(p, n) * q, n))

    @staticmethod
    def _blk_add(x, y, sign=1):
        if y is None:
            return x
        if x is None:
            return y if sign == 1 else (y[0], -y[1])
        if x[0] != y[0]:
            if y[1] == 0:
                return x
            if x[1] == 0:
                return y if sign == 1 else (y[0], -y[1])
            raise Mixed("the sum of a circulant and a Hankel block")
        return (x[0], x[1] + y[1] if sign == 1 else x[1] - y[1])

    def __add__(self, other):
        return BlockMatrix(self.n, [[self._blk_add(a, b) for a, b in zip(ra, rb)] for ra, rb in zip(self.b, other.b)])

    def __sub__(self, other):
        return BlockMatrix(self.n, [[self._blk_add(a, b, -1) for a, b in zip(ra, rb)]
                                    for ra, rb in zip(self.b, other.b)])

    def scale(self, s):
        """s · self for an integer s."""
        return BlockMatrix(self.n, [[None if x is None else (x[0], x[1] * s) for x in r] for r in self.b])

    def __mul__(self, other):
        A, B = self.b, other.b
        out = []
        for i in range(2):
            row = []
            for j in range(2):
                acc = None
                for k in range(2):
                    acc = self._blk_add(acc, self._blk_mul(A[i][k], B[k][j]))
                row.append(acc)
            out.append(row)
        return BlockMatrix(self.n, out)

    def T(self):
        """The transpose: the off-diagonal blocks swap, each block is transposed."""
        n = self.n

        def t(x):
            return x if x is None or x[0] == "X" else ("C", _reflect(x[1], n))
        (a, b), (c, d) = self.b
        return BlockMatrix(n, [[t(a), t(c)], [t(b), t(d)]])

    # -- comparison and the dense matrix ----------------------------------------------
    def _block_dense(self, x):
        n = self.n
        if x is None:
            return [[flint.fmpz(0)] * n for _ in range(n)]
        kind, p = x
        c = [p[k] for k in range(n)]
        if kind == "C":
            return [[c[(j - i) % n] for j in range(n)] for i in range(n)]
        return [[c[(i + j) % n] for j in range(n)] for i in range(n)]

    def __eq__(self, other):
        for ra, rb in zip(self.b, other.b):
            for x, y in zip(ra, rb):
                zx, zy = x is None or x[1] == 0, y is None or y[1] == 0
                if zx or zy:
                    if not (zx and zy):
                        return False
                elif x[0] == y[0]:
                    if x[1] != y[1]:
                        return False
                elif self._block_dense(x) != self._block_dense(y):  # both circulant and Hankel
                    return False
        return True

    __hash__ = None

    def entries(self):
        """The entries of the 2n×2n matrix, row by row."""
        n = self.n
        blocks = [[self._block_dense(x) for x in r] for r in self.b]
        return [t for bi in range(2) for i in range(n) for t in blocks[bi][0][i] + blocks[bi][1][i]]

    def dense(self):
        """The 2n×2n ``fmpz_mat``."""
        return fmpz_mat(2 * self.n, 2 * self.n, self.entries())
