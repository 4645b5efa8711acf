"""The Lie–Poisson family of Petrera & Suris: the system, its fields and their integrals."""

from .system import (DEFAULT_EPS, DEFAULT_VECTORS, DEFAULT_X0, LiePoissonField, LiePoissonSystem,
                     b0_signs, default_system, involution_circulant, random_point, rational_sign_patterns)

__all__ = ["DEFAULT_EPS", "DEFAULT_VECTORS", "DEFAULT_X0", "LiePoissonField", "LiePoissonSystem", "b0_signs",
           "default_system", "involution_circulant", "random_point", "rational_sign_patterns"]
