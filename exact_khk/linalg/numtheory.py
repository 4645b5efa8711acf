"""Small number theory for the cyclotomic structure of Q[t]/(tⁿ − 1): the Möbius
function and Ramanujan sums (the traces Tr_{Q(ζ_q)/Q}(ζ_q^k)).

>>> [ramanujan_sum(6, k) for k in range(6)]
[2, 1, -1, -2, -1, 1]
"""

from __future__ import annotations

from math import gcd


def _mobius(m: int) -> int:
    result, p = 1, 2
    while p * p <= m:
        if m % p == 0:
            m //= p
            if m % p == 0:
                return 0
            result = -result
        p += 1
    return -result if m > 1 else result


def ramanujan_sum(q: int, k: int) -> int:
    """c_q(k) = Σ_{1<=j<=q, gcd(j,q)=1} ω_q^{jk} = Σ_{m | gcd(q,k)} μ(q/m) m."""
    g = gcd(q, k)
    return sum(_mobius(q // m) * m for m in range(1, g + 1) if g % m == 0)
