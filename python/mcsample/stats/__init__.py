"""Statistics that prove samplers right, for mcsample's own and for yours.

- :func:`chi2_test`: Pearson's chi-square goodness of fit of a sampler
  against its density, by the method of Mitsuba 3's ``mitsuba.chi2``: map the
  samples to a 2D parameter box, histogram them, integrate the density over
  each cell (trapezoid rule, ``ires`` points per cell and axis, or unbiased
  jittered integration for densities that jump inside cells), pool cells
  with an expected count below 5, and compare the p-value with a
  Šidák-corrected significance level; the test runs on the histogram and
  on two coarser ones (8×8 and 32×32 cells merged), which find a small
  error spread over a large part of the domain that the fine one misses.
- :func:`two_sample_test`: the chi-square test of homogeneity of two samplers
  that have no density.
- image comparison: :func:`mse`, :func:`relmse`, :func:`image_ztest`, and
  :func:`render_ztest` for two renders.

Domains map target points to a parameter box whose boundary is the domain's
boundary (so no cell straddles an edge of the support) and give the Jacobian
from the box's measure to the target measure (per steradian on the sphere,
per unit area on the plane, per unit length on an interval).
"""


from .chi2 import Chi2Result, chi2_test, two_sample_test
from .domains import (ConeDomain, DiskDomain, Domain, DomainLike, EnvMapDomain, HemisphereDomain,
                      IntervalDomain, PlanarDomain, SphericalDomain, make_domain)
from .images import ZTestResult, image_ztest, luminance, mse, relmse, render_ztest

__all__ = [
    "Chi2Result",
    "ConeDomain",
    "DiskDomain",
    "Domain",
    "DomainLike",
    "EnvMapDomain",
    "HemisphereDomain",
    "IntervalDomain",
    "PlanarDomain",
    "SphericalDomain",
    "chi2_test",
    "image_ztest",
    "luminance",
    "make_domain",
    "mse",
    "relmse",
    "render_ztest",
    "two_sample_test",
    "ZTestResult",
]
