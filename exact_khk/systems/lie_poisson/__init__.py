"""The Lie–Poisson family of Petrera & Suris: the system, its fields and their integrals, and its
fast Kahan steps (steps.py, offered through ``LiePoissonField.structured_steps``; circulant.py,
circulant_dft.py, split.py, dihedral.py; the rule table paths.py)."""

from .system import (DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0, LiePoissonField, LiePoissonSystem,
                     b0_signs, default_system, involution_circulant, random_point, rational_sign_patterns)

__all__ = ["DEFAULT_EPS", "DEFAULT_VECTORS", "DEFAULT_X0", "LiePoissonField", "LiePoissonSystem", "b0_signs",
           "default_system", "involution_circulant", "random_point", "rational_sign_patterns"]
