"""Certification: records, generic checks, the Lie–Poisson theorems, evidence of other kinds.

:func:`certify` certifies any :class:`~exact_khk.systems.base.System` by the claims of the
registry it declares (:mod:`~exact_khk.certification.claims`, run by
:mod:`~exact_khk.certification.engine`); a system whose certificate takes involution signs
(``certificate_options``: the Lie–Poisson family) takes them, and Poisson points, identities and
proofs, by :mod:`~exact_khk.certification.lie_poisson`.
"""

from __future__ import annotations

from exact_khk.parsing import any_int_digits


@any_int_digits()  # numbers of any size print (e.g. an eps of 5000 digits)
def certify(system=None, x0=None, eps=None, steps: int = 20, arith=None, **options):
    """Certify ``system`` (default: the built-in Lie–Poisson system) on the orbit of
    ``x0``; see :func:`exact_khk.certification.lie_poisson.certify` (options
    ``signs``, ``poisson_points``, ``identities``, ``prove``) and
    :func:`exact_khk.certification.engine.certify_system` (options ``claims``, ``identities``, ``prove``)."""
    from exact_khk.certification import engine, lie_poisson
    from exact_khk.errors import InputError
    from exact_khk.systems.catalogue import System, resolve

    if isinstance(system, (str, bytes)) or hasattr(system, "__fspath__"):
        system = resolve(system)  # a catalogue name or a system file, as on the command line
    if system is not None and not isinstance(system, System):
        raise InputError(f"system: expected a System (e.g. System.load('euler-top')) or a catalogue name, "
                         f"got {type(system).__name__}")
    if system is None or "signs" in system.certificate_options:  # a certificate over involutions it chooses
        return lie_poisson.certify(system, x0, eps, steps, arith, **options)
    other = sorted(set(options) - {"claims", "progress", "identities", "prove"})
    if other:
        raise InputError(f"{other[0]}: an option of Lie-Poisson systems only; {system.name} takes claims=, "
                         f"identities=, prove=")
    return engine.certify_system(system, x0, eps, steps, arith, **options)
