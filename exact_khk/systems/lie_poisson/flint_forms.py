"""The matrices the Lie–Poisson certificate compares, as python-flint ``fmpq_mat``
(the ``flint`` arithmetic only): whole products and solves in C, derivatives by
closed forms instead of dual numbers.

The certificate's claims (:mod:`exact_khk.certification.claims`) use :class:`FlintForms`
(:meth:`LiePoissonSystem.fast_forms`) when the arithmetic's elements are ``fmpq``; every other arithmetic (``fraction``,
``gmpy2``, cyclotomic, finite fields, floating, balls) keeps the generic
list-of-rows code and the dual-number derivatives.  Each quantity is the same
rational matrix as its generic counterpart (tests compare them with ``==``);
only the route differs.  With x = (u, v), E_m = J(e_m) (m < n) and M = Hs:

* J(x) = Σ_{m<n} u_m E_m is linear in u and free of v, so ∂_m J = E_m for
  m < n and 0 for m ≥ n; E_m X and X E_m are signed permutations of rows and
  columns (no product): (E_m X)_i = X_{n+(m−i) mod n}, (E_m X)_{n+i} =
  −X_{(m−i) mod n};
* Π = J − ε² K² J with K = J M, L = M J (K² J = J L²), so
  ∂_m Π = E_m − ε² (E_m L² + K E_m L + K² E_m)  (m < n), ∂_m Π = 0 (m ≥ n);
* S = J M, (J M)² = Σ_l q_l A^l with q_l = Σ_i S²[i][σ_l(i)]/(2n) (σ_l the
  shift of :func:`~exact_khk.systems.lie_poisson.invariants.shift_index`), and
  ∂_m S² = E_m M S + S E_m M;
* f'(x) = J(x) M + [E_0 y, …, E_{n−1} y, 0, …, 0] with y = M x, and
  dΦ(x) = (I − εf'(x))^{-1}(I + εf'(Φ(x)));
* one solve for all the integrals at a point: for an involution B (B² = I) that
  commutes with every Hs E_m (so with Hs J(x) for every x; B = Bc ⊕ Bc with Bc
  circulant does, Hs J(x) having circulant blocks), (B Hs J)² = (Hs J)², so
  K̃_B(x) = xᵀ (I − ε²(Hs J)²)^{-1} B Hs x = xᵀ B z with z = R^{-1} Hs x, R the
  matrix of H̃.  :meth:`FlintForms.share_integrals` verifies these hypotheses
  exactly, once per involution (not assumed); z comes from the structured solve
  of :mod:`exact_khk.systems.lie_poisson.circulant`.  For the same reason R_{B Hs} = R, so the
  gradients of all the integrals share w = R^{-T} x (one dense solve per point),
  while each z_B = R^{-1} B Hs x is solved on its own (from B Hs, not as B z: the
  claim ∇K̃ = B ∇H̃ is then not built into the computation).

>>> from exact_khk.arith import get_arith
>>> from exact_khk.systems.lie_poisson import default_system
>>> from exact_khk.systems.lie_poisson.invariants import Pi
>>> from exact_khk.linalg.flintmat import rows
>>> s, ar = default_system(), get_arith("flint")
>>> F = FlintForms(s, ar("1/10"))
>>> x = [ar(t) for t in (1, 2, -1, "1/2", 0, 1)]
>>> rows(F.Pi(x)) == Pi(s, x, "1/10", ar)
True
>>> F.jacobiator(x) == [0] * 20
True
"""

from __future__ import annotations

import flint

from exact_khk.errors import NotRationalError, SingularStepError
from exact_khk.systems.lie_poisson import circulant
from exact_khk.linalg.dense import SingularMatrix
from exact_khk.systems.lie_poisson.dihedral import BlockMatrix, Mixed
from exact_khk.linalg.flintmat import column, fmpq_mat, fmpz_mat, mat, signed_columns, signed_rows
from exact_khk.systems.lie_poisson.invariants import _pole, shift_index


class FlintForms:
    """Closed forms of Π, ∂Π, q_l, ∇q_l, f' and dΦ for one system and one ε
    (an ``fmpq``), as ``fmpq_mat``; constant matrices are built once.

    Internally most forms are integer matrices (``fmpz_mat``: no gcd per entry)
    with one scalar denominator: a point x = ξ/d (ξ integer, d its common
    denominator), Hs = Hn/h, ε = p/q; then J(x) = J(ξ)/d and, e.g.,
    Π(x) = (q²h²d² J(ξ) − p² K² J(ξ)) / (q²h²d³) with K = J(ξ) Hn."""

    def __init__(self, system, eps):
        self.system, self.n, self.N = system, system.n, system.dim
        self.eps = eps
        self.e2 = eps * eps
        n, N = self.n, self.N
        ident = [int(i == j) for i in range(N) for j in range(N)]
        self.I, self.Iz = fmpq_mat(N, N, ident), fmpz_mat(N, N, ident)
        self._hess = {}
        # E_m = J(e_m) as the signed permutation it applies to rows: (E_m X)[r] = sign · X[src]
        self._E = [([n + (m - i) % n for i in range(n)] + [(m - i) % n for i in range(n)],
                    [1] * n + [-1] * n) for m in range(n)]
        # (X E_m)[:, c] = sign · X[:, src]: columns j < n take −X[:, n + (m − j) mod n],
        # columns n + j take X[:, (m − j) mod n]
        self._Ecol = [([n + (m - j) % n for j in range(n)] + [(m - j) % n for j in range(n)],
                       [-1] * n + [1] * n) for m in range(n)]
        self._Emat = [signed_rows(self.I, *self._E[m]) for m in range(n)]
        self._Ezmat = [signed_rows(self.Iz, *self._E[m]) for m in range(n)]
        self.shifts = [shift_index(n, l) for l in range(n)]
        self.p, self.q_ = eps.p, eps.q

    def hessian(self, field):
        """The field's constant matrix M as an ``fmpq_mat`` and as (Mn, m), M = Mn/m (cached per field)."""
        key = id(field)
        hit = self._hess.get(key)
        if hit is None or hit[0] is not field:
            M = mat(field.hessian)
            hit = self._hess[key] = (field, M, M.numer_denom())
        return hit[1]

    def _hessian_int(self, field):
        self.hessian(field)
        return self._hess[id(field)][2]

    @property
    def Hs(self):
        return self.hessian(self.system.field("f"))

    def J(self, x):
        """J(x) = [[0, X(u)], [−X(u), 0]]."""
        return self._J(list(x), fmpq_mat, flint.fmpq(0))

    def _J(self, u, kind, zero):
        n, N = self.n, self.N
        top = [t for i in range(n) for t in [zero] * n + [u[(i + j) % n] for j in range(n)]]
        bottom = [t for i in range(n) for t in [-u[(i + j) % n] for j in range(n)] + [zero] * n]
        return kind(N, N, top + bottom)

    def J_int(self, x):
        """(J(ξ), d) with J(x) = J(ξ)/d (x = ξ/d, ξ integer)."""
        _, d, Jz = self._cleared(x)
        return Jz, d

    def _cleared(self, x):
        """(ξ as an N×1 fmpz_mat, d) with x = ξ/d, and J(ξ)."""
        xi, d = fmpq_mat(self.N, 1, list(x)).numer_denom()
        return xi, d, self._J(xi.entries()[:self.n], fmpz_mat, flint.fmpz(0))

    # --- the Poisson tensor --------------------------------------------------------

    def Pi_int(self, x):
        """(Πz, c) with Π(x) = J − ε² J Hs J Hs J = Πz / c (Πz integer)."""
        _, d, Jz = self._cleared(x)
        Hn, h = self._hessian_int(self.system.field("f"))
        p, q = self.p, self.q_
        K = Jz * Hn
        return Jz * (q * h * d) ** 2 - (K * (K * Jz)) * p ** 2, q ** 2 * h ** 2 * d ** 3

    def Pi(self, x):
        """Π(x) = J − ε² J Hs J Hs J (the definition)."""
        Pz, c = self.Pi_int(x)
        return fmpq_mat(Pz) / c

    def q(self, x):
        """[q_0, …, q_{n−1}]: (J Hs)² = Σ_l q_l A^l, q_l = Σ_i S²[i][σ_l(i)]/(2n)."""
        S = self.J(x) * self.Hs
        return [t / (2 * self.n) for t in self._traces(S * S, flint.fmpq(0))]

    def _traces(self, S2, zero):
        """[Σ_i S2[i][σ_l(i)] for l < n]."""
        N, flat = self.N, S2.entries()
        return [sum((flat[i * N + s] for i, s in enumerate(sig)), zero) for sig in self.shifts]

    def Pi_sides(self, x):
        """Π by its definition and by (1 − ε² q_0) J − ε² Σ_{l≥1} q_l A^l J = (I − ε² Σ_l q_l A^l) J,
        as entries: both times 2n·q²h²d³ (integers) when they agree, else the rationals
        themselves (so that a failure reports the rational residual)."""
        N, n = self.N, self.n
        _, d, Jz = self._cleared(x)
        Hn, h = self._hessian_int(self.system.field("f"))
        p, q = self.p, self.q_
        S = Jz * Hn  # S = J Hs = (Jz Hn)/(d h);  q_l = Q_l / (2n d² h²)
        Q = self._traces(S * S, flint.fmpz(0))
        C = [flint.fmpz(0)] * (N * N)
        for l, sig in enumerate(self.shifts):
            for j, s_ in enumerate(sig):
                C[j * N + s_] -= p ** 2 * Q[l]
        for j in range(N):
            C[j * N + j] += 2 * n * (q * h * d) ** 2
        right = fmpz_mat(N, N, C) * Jz
        Pz, c = self.Pi_int(x)
        left = Pz * (2 * n)
        if left == right:
            return (), ()
        return (fmpq_mat(left) / (2 * n * c)).entries(), (fmpq_mat(right) / (2 * n * c)).entries()

    def Pi_from_q(self, x):
        """Π(x) = (1 − ε² q_0) J − ε² Σ_{l≥1} q_l A^l J = (I − ε² Σ_l q_l A^l) J (rational route)."""
        N, J = self.N, self.J(x)
        q = self.q(x)
        C = [flint.fmpq(0)] * (N * N)
        for l, sig in enumerate(self.shifts):
            c = -self.e2 * q[l]
            for j, s in enumerate(sig):
                C[j * N + s] += c
        for j in range(N):
            C[j * N + j] += 1
        return fmpq_mat(N, N, C) * J

    def _dPi_int(self, x):
        """([q²h²d² ∂_mΠ for m < n] as fmpz_mat, q²h²d²); ∂_mΠ = 0 for m ≥ n."""
        _, d, Jz = self._cleared(x)
        Hn, h = self._hessian_int(self.system.field("f"))
        p, q = self.p, self.q_
        K, L = Jz * Hn, Hn * Jz
        K2, L2 = K * K, L * L
        c = (q * h * d) ** 2
        out = []
        for m in range(self.n):
            src, sign = self._E[m]
            csrc, csign = self._Ecol[m]
            inner = signed_rows(L2, src, sign) + K * signed_rows(L, src, sign) + signed_columns(K2, csrc, csign)
            out.append(self._Ezmat[m] * c - inner * p ** 2)
        return out, c

    def jacobiator(self, x):
        """All cyclic sums Σ_m (Π_im ∂_mΠ_jk + Π_jm ∂_mΠ_ki + Π_km ∂_mΠ_ij), i < j < k
        (order as in :func:`~exact_khk.certification.checks.jacobiator`), from the integer
        tensor T[i] = Σ_m Πz_im ∂_mΠz: by circulant/Hankel blocks (:meth:`_jacobi_tensor_blocks`)
        where the system has them, else by one dense product (:meth:`_jacobi_tensor_dense`)."""
        try:
            got = self._jacobi_tensor_blocks(x)
        except Mixed:
            got = None
        return self._cyclic_sums(*(got or self._jacobi_tensor_dense(x)))

    def _jacobi_tensor_dense(self, x):
        """(T flattened, den): T = Πz[:, :n] · [∂_0Πz; …; ∂_{n−1}Πz] (each flattened to a row)."""
        n, N = self.n, self.N
        Pz, c = self.Pi_int(x)
        D, c2 = self._dPi_int(x)
        P = Pz.entries()
        Pu = fmpz_mat(N, n, [P[i * N + m] for i in range(N) for m in range(n)])
        return (Pu * fmpz_mat(n, N * N, [t for Dm in D for t in Dm.entries()])).entries(), c * c2

    def _jacobi_tensor_blocks(self, x):
        """(T flattened, den) as :meth:`_jacobi_tensor_dense`, with T[i] the directional
        derivative of Π along (Π_i0, …, Π_i,n−1, 0, …, 0): J is linear, so
        Σ_m c_m ∂_mΠz = (qhd)² J(c) − p² (J(c) L² + K J(c) L + K² J(c)) (K = J(ξ) Hn,
        L = Hn J(ξ)), a few products of circulant and Hankel blocks per row i.  None
        if the Hessian's blocks are not cyclic Hankel."""
        Hb = self._hessian_blocks(self.system.field("f"))
        if Hb is None:
            return None
        n, N = self.n, self.N
        xi, d = fmpq_mat(N, 1, list(x)).numer_denom()
        _, h = self._hessian_int(self.system.field("f"))
        p, q = self.p, self.q_
        Jb = self._J_blocks(xi)
        K, L = Jb * Hb, Hb * Jb
        K2, L2 = K * K, L * L
        c2 = (q * h * d) ** 2
        Pb, c = self.Pi_blocks(x)
        P = Pb.entries()
        T = []
        for i in range(N):
            u = P[i * N:i * N + n]
            Jc = BlockMatrix.hankel_blocks(n, [[None, u], [[-t for t in u], None]])
            Di = Jc.scale(c2) - (Jc * L2 + K * Jc * L + K2 * Jc).scale(p ** 2)
            T.extend(Di.entries())
        return T, c * c2

    def _cyclic_sums(self, T, den):
        N = self.N
        NN = N * N
        out = []
        for i in range(N):
            for j in range(i + 1, N):
                for k in range(j + 1, N):
                    out.append(flint.fmpq(T[i * NN + j * N + k] + T[j * NN + k * N + i] + T[k * NN + i * N + j],
                                          den))
        return out

    def q_gradients(self, x):
        """[∇q_0, …, ∇q_{n−1}] (each of length 2n; zero in the v coordinates):
        ∂_m S² = E_m Hs S + S E_m Hs = (E_m Hn Sz + Sz E_m Hn)/(d h²), Sz = J(ξ) Hn."""
        n, N = self.n, self.N
        _, d, Jz = self._cleared(x)
        Hn, h = self._hessian_int(self.system.field("f"))
        S = Jz * Hn
        HS = Hn * S
        den = 2 * n * d * h ** 2
        cols = []  # cols[m] = [∂_m q_l for l]
        for m in range(n):
            src, sign = self._E[m]
            dS2 = signed_rows(HS, src, sign) + S * signed_rows(Hn, src, sign)
            cols.append([flint.fmpq(t, den) for t in self._traces(dS2, flint.fmpz(0))])
        zero = flint.fmpq(0)
        return [[cols[m][l] for m in range(n)] + [zero] * (N - n) for l in range(n)]

    # --- the Kahan map's Jacobian -----------------------------------------------------

    def field_jacobian(self, field, x):
        """f'(x) = J(x) M + [E_0 y, …, E_{n−1} y, 0, …, 0], y = M x."""
        Fz, den = self._field_jacobian_int(field, x)
        return fmpq_mat(Fz) / den

    def _field_jacobian_int(self, field, x):
        """(Fz, m d) with f'(x) = Fz/(m d), M = Mn/m, x = ξ/d."""
        n, N = self.n, self.N
        xi, d, Jz = self._cleared(x)
        Mn, m = self._hessian_int(field)
        y = (Mn * xi).entries()
        extra = [flint.fmpz(0)] * (N * N)
        for k in range(n):
            for i in range(n):
                extra[i * N + k] = y[n + (k - i) % n]
                extra[(n + i) * N + k] = -y[(k - i) % n]
        return Jz * Mn + fmpz_mat(N, N, extra), m * d

    def poisson_map_cleared(self, phi, x, y, Pi_x, Pi_y):
        """Whether dΦ Π(x) dΦᵀ = Π(y) (y = Φ(x)), decided with the identity multiplied by
        I − εf'(x) on the left and its transpose on the right:
        (I + εf'(y)) Π(x) (I + εf'(y))ᵀ = (I − εf'(x)) Π(y) (I − εf'(x))ᵀ — equivalent
        where the step is defined (I − εf'(x) invertible) — in integers, without the
        solve and without dΦ's large entries.  ``Pi_x``, ``Pi_y``: :meth:`Pi_int` results."""
        p, q = self.p, self.q_
        Fx, ax = self._field_jacobian_int(phi.field, x)  # f'(x) = Fx/ax
        Fy, ay = self._field_jacobian_int(phi.field, y)
        A = self.Iz * (q * ax) - Fx * p  # (I − εf'(x)) · q ax
        B = self.Iz * (q * ay) + Fy * p  # (I + εf'(y)) · q ay
        (Px, cx), (Py, cy) = Pi_x, Pi_y
        return (B * Px * B.transpose()) * ((q * ax) ** 2 * cy) == (A * Py * A.transpose()) * ((q * ay) ** 2 * cx)

    # --- the same in circulant/Hankel blocks (polynomial products) ----------------------

    def _hessian_blocks(self, field):
        """The integer Hessian Mn (M = Mn/m) as a :class:`BlockMatrix` of Hankel blocks, or
        None if its blocks are not cyclic Hankel (checked against the dense Mn, once)."""
        cache = self.__dict__.setdefault("_hblocks", {})
        key = id(field)
        if key not in cache or cache[key][0] is not field:
            Mn, m = self._hessian_int(field)
            st = circulant.circulant_structure(field)
            out = None
            if st is not None:
                rows = [[[t * int(m) for t in w] for w in r] for r in st.m]
                if all(t.denominator == 1 for r in rows for w in r for t in w):
                    Mb = BlockMatrix.hankel_blocks(self.n, [[[int(t) for t in w] for w in r] for r in rows])
                    out = Mb if Mb.dense() == Mn else None
            cache[key] = (field, out)
        return cache[key][1]

    def _J_blocks(self, xi):
        u = xi.entries()[:self.n]
        return BlockMatrix.hankel_blocks(self.n, [[None, u], [[-t for t in u], None]])

    def Pi_blocks(self, x):
        """(Πb, c): Π(x) = Πb/c as a :class:`BlockMatrix` (the same as :meth:`Pi_int`), or None."""
        Hb = self._hessian_blocks(self.system.field("f"))
        if Hb is None:
            return None
        xi, d = fmpq_mat(self.N, 1, list(x)).numer_denom()
        _, h = self._hessian_int(self.system.field("f"))
        p, q = self.p, self.q_
        Jb = self._J_blocks(xi)
        K = Jb * Hb
        return Jb.scale((q * h * d) ** 2) - (K * (K * Jb)).scale(p ** 2), q ** 2 * h ** 2 * d ** 3

    def _field_jacobian_blocks(self, field, Mb, x):
        """(Fb, m d) with f'(x) = Fb/(m d) (circulant blocks): J(ξ) Mn + [E_k Mn ξ]_k."""
        n = self.n
        xi, d = fmpq_mat(self.N, 1, list(x)).numer_denom()
        Mn, m = self._hessian_int(field)
        y = (Mn * xi).entries()
        Ey = BlockMatrix.circulant_blocks(n, [[y[n:], None], [[-t for t in y[:n]], None]])
        return self._J_blocks(xi) * Mb + Ey, m * d

    def poisson_map_blocks(self, phi, x, y, Pi_x, Pi_y):
        """:meth:`poisson_map_cleared` with :meth:`Pi_blocks` and products of circulant and
        Hankel blocks; None where the field has no such structure."""
        Mb = self._hessian_blocks(phi.field)
        if Mb is None or Pi_x is None or Pi_y is None:
            return None
        p, q = self.p, self.q_
        try:
            Fx, ax = self._field_jacobian_blocks(phi.field, Mb, x)
            Fy, ay = self._field_jacobian_blocks(phi.field, Mb, y)
            I = BlockMatrix.identity(self.n)
            A = I.scale(q * ax) - Fx.scale(p)
            B = I.scale(q * ay) + Fy.scale(p)
            (Px, cx), (Py, cy) = Pi_x, Pi_y
            return (B * Px * B.T()).scale((q * ax) ** 2 * cy) == (A * Py * A.T()).scale((q * ay) ** 2 * cx)
        except Mixed:
            return None

    def dPhi(self, phi, x, y):
        """dΦ(x) = (I − εf'(x))^{-1} (I + εf'(y)) for the map ``phi`` (step ε of this
        object), y = Φ(x) (the next orbit point, already known)."""
        e = self.eps
        try:
            return (self.I - e * self.field_jacobian(phi.field, x)).solve(
                self.I + e * self.field_jacobian(phi.field, y))
        except ZeroDivisionError:
            raise SingularStepError([str(t) for t in x], str(e)) from None

    # --- the integrals: one solve per point -------------------------------------------

    def _ring(self, purpose):
        """A :class:`~exact_khk.systems.lie_poisson.circulant.CirculantRing` of its own for each kind of
        solve: the ring adapts the first precision of its fixed-point division to the last
        answer's height, and the H̃ solves, the J((x+x~)/2) solves and the Kahan steps
        (which use the shared ring) have answers of different heights."""
        rings = self.__dict__.setdefault("_rings", {})
        if purpose not in rings:
            rings[purpose] = circulant.CirculantRing(self.n)
        return rings[purpose]

    def share_integrals(self, integrals):
        """``integrals``: {name: :class:`~exact_khk.systems.lie_poisson.invariants.HtildeIntegral`}
        (H̃ itself, ``signs`` None, and K̃[signs]).  Returns the names of those that
        :meth:`share_matrices` shares (non-rational patterns are not: their B is not rational);
        ``base`` is the name of H̃."""
        pairs = {}
        for name, fn in integrals.items():
            try:
                pairs[name] = (fn.fld, None if fn.signs is None else self.system.involution(fn.signs))
            except NotRationalError:
                continue
        self.base = next((name for name, fn in integrals.items() if fn.signs is None), None)
        shared = self.share_matrices(pairs)
        return shared if self.base in shared else set()

    def share_matrices(self, involutions):
        """``involutions``: {key: (field, B as rows or None for H~ itself)}.  Returns the
        keys whose integral is xᵀ B z (see the module docstring), after checking exactly
        that M_key = B Hs, B² = I and B Hs E_m = Hs E_m B for m < n."""
        Hs, shared = self.Hs, {}
        HE = [Hs * self._Emat[m] for m in range(self.n)]
        for key, (field, B) in involutions.items():
            Bm = self.I if B is None else mat(B)
            if (self.hessian(field) == Bm * Hs and Bm * Bm == self.I
                    and all(Bm * X == X * Bm for X in HE)):
                shared[key] = Bm
        self._shared = shared
        self._structure = circulant.circulant_structure(self.system.field("f"))
        return set(shared)

    def pole(self, ar, x):
        """The PoleError of H̃ at x (a singular solve of the shared integrals)."""
        return _pole(ar, list(x), self.eps)

    def htilde_solution(self, x, field=None):
        """z = R^{-1} M x (R = I − ε²(M J(x))², M the Hessian of ``field``, default f's)
        by the 2×2 solve over Q[t]/(tⁿ − 1), so that H̃_M(x) = xᵀ z; raises
        :class:`SingularMatrix` at a pole.  The steps of
        :func:`exact_khk.systems.lie_poisson.circulant.exact_htilde`, keeping the vector."""
        st = self._structure if field is None else circulant.circulant_structure(field)
        return self._solutions(x, st, [st])[0]

    def htilde_solutions(self, x, fields):
        """[R^{-1} M x for the Hessian M of each field] with H̃'s matrix R (one division
        over Q[t]/(tⁿ − 1) for all): for the shared integrals, whose R_M is R."""
        return self._solutions(x, self._structure, [circulant.circulant_structure(f) for f in fields])

    def _solutions(self, x, st, rhs_structures):
        """z_i = R_st^{-1} M_i x (M_i the Hessian of ``rhs_structures[i]``) by
        :func:`~exact_khk.systems.lie_poisson.circulant.htilde_solve` in a ring of this purpose's own."""
        R = self._ring("htilde")
        W, delta = circulant.htilde_solve(R, st, rhs_structures, *circulant.point_polys(list(x)), self.eps)
        dens = [R.integer_hankel(sti, reflected=True)[1] for sti in rhs_structures]
        return [[flint.fmpq(c, delta * dmi) for c in circulant.reflect(R.coeffs(W[2 * i]))
                 + circulant.reflect(R.coeffs(W[2 * i + 1]))] for i, dmi in enumerate(dens)]

    def htilde_adjoint(self, x):
        """w = R^{-T} x for H̃'s matrix R = I − ε²(Hs J(x))² (dense, in integers:
        R = Rz/(q h d)², Rz = (q h d)² I − p² (Hn J(ξ))²); SingularMatrix at a pole."""
        xi, d, Jz = self._cleared(x)
        Hn, h = self._hessian_int(self.system.field("f"))
        S = Hn * Jz
        c = (self.q_ * h * d) ** 2
        Rz = self.Iz * c - (S * S) * self.p ** 2
        try:
            w = Rz.transpose().solve(xi)
        except ZeroDivisionError:
            raise SingularMatrix("H~ has a pole") from None
        return (w * flint.fmpq(c, d)).entries()

    def gradient(self, field, x, z, w):
        """∇H̃_M at x (M the Hessian of ``field``) by the closed form of
        :func:`~exact_khk.systems.lie_poisson.invariants.grad_Htilde` from z = R_M^{-1} M x
        and w = R_M^{-T} x, with matrix–vector products only (S = M J(x)):
        ∂_k H̃ = z_k + (Mᵀw)_k + ε² [ (Mᵀw)ᵀ E_k S z + (Mᵀ Sᵀ w)ᵀ E_k z ] (k < n), z_k + (Mᵀw)_k (k ≥ n).
        In integers (M = Mn/m, x = ξ/d, z = Z/dz, w = W/dw): a = Mnᵀ W/(m dw),
        S z = Mn J(ξ) Z/(m d dz), Mᵀ Sᵀ w = Mnᵀ J(ξ)ᵀ Mnᵀ W/(m² d dw), so both brackets
        have the denominator m² d dw dz; the forms uᵀ E_k v for all k are one product in
        Z[t]/(tⁿ − 1): Σ_k (uᵀ E_k v) t^k = u_u(t) v_v(t) − u_v(t) v_u(t)."""
        n, N = self.n, self.N
        _, d, Jz = self._cleared(x)
        Mn, m = self._hessian_int(field)
        Mt = Mn.transpose()
        Z, dz = column(z).numer_denom()
        W, dw = column(w).numer_denom()
        MtW = Mt * W
        a, b, c, Ze = MtW.entries(), (Mn * (Jz * Z)).entries(), (Mt * (Jz.transpose() * MtW)).entries(), Z.entries()
        poly = flint.fmpz_poly
        forms = poly(a[:n]) * poly(b[n:]) - poly(a[n:]) * poly(b[:n]) + poly(c[:n]) * poly(Ze[n:]) \
            - poly(c[n:]) * poly(Ze[:n])
        folded = [flint.fmpz(0)] * n
        for k in range(forms.degree() + 1):
            folded[k % n] += forms[k]
        p, q = self.p, self.q_
        den_a, den_f = m * dw, (q * m) ** 2 * d * dw * dz
        return [flint.fmpq(Ze[k], dz) + flint.fmpq(a[k], den_a) + (flint.fmpq(p * p * folded[k], den_f) if k < n else 0)
                for k in range(N)]

    @staticmethod
    def bracket(g1, P, g2):
        """g1ᵀ P g2 for a matrix given as (Pn, dp), P = Pn/dp, in integers."""
        Pn, dp = P
        G1, d1 = column(g1).numer_denom()
        G2, d2 = column(g2).numer_denom()
        return flint.fmpq((G1.transpose() * (Pn * G2)).entries()[0], d1 * d2 * dp)

    def integral_values(self, x, z=None):
        """{key: xᵀ B_key z} for the shared integrals (one solve, or ``z`` if given); raises
        SingularMatrix at a pole.  In integers: the rows xᵀ B_key for all keys are one
        product (Σ_key B_keyᵀ stacked) · ξ, their products with z one more."""
        keys = list(self._shared)
        if getattr(self, "_stack", None) is None or self._stack[0] != keys:
            Bt = fmpq_mat(len(keys) * self.N, self.N,
                          [t for key in keys for t in self._shared[key].transpose().entries()])
            self._stack = (keys,) + Bt.numer_denom()
        _, Bn, db = self._stack
        xi, dx = fmpq_mat(self.N, 1, list(x)).numer_denom()
        Zc, dz = column(self.htilde_solution(x) if z is None else z).numer_denom()
        Y = fmpz_mat(len(keys), self.N, (Bn * xi).entries())
        den = db * dx * dz
        return {key: flint.fmpq(t, den) for key, t in zip(keys, (Y * Zc).entries())}

    def htilde_definition(self, x, y):
        """h(x, y) = (2ε)^{-1} xᵀ J(m)^{-1} y, m = (x + y)/2, with J(m) solved over the
        circulant ring: J(m) z = y is X(m_u) z_v = y_u, X(m_u) z_u = −y_v, and a Hankel
        system X(w) s = r is w(t)·s̄(t) = r(t) in Q[t]/(tⁿ − 1) (s̄ the reflection).
        Raises :class:`SingularMatrix` where J(m) is singular."""
        n = self.n
        Rg = self._ring("definition")
        half = flint.fmpq(1, 2)
        mu, dm = fmpq_mat(n, 1, [(a + b) * half for a, b in zip(x[:n], y[:n])]).numer_denom()
        yu, yv, dy = circulant.point_polys(list(y))
        # X(m_u) = X(mu)/dm, so X(mu) s = Y_part gives z_part = ± s · dm / dy
        W, delta = circulant.split_divide(Rg, flint.fmpz_poly(mu.entries()), [yu, yv])
        # z_v = s_v·dm/(dy δ), z_u = −s_u·dm/(dy δ)
        s_v, s_u = (circulant.reflect(Rg.coeffs(w)) for w in W)
        X, dx = fmpq_mat(self.N, 1, list(x)).numer_denom()
        Xe = X.entries()
        dot = sum((Xe[n + i] * s_v[i] - Xe[i] * s_u[i] for i in range(n)), flint.fmpz(0))
        return flint.fmpq(dot * dm, dx * dy * delta) / (2 * self.eps)
