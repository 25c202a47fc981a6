"""Warps from the unit square to disks, spheres, hemispheres, lobes and
triangles, each with its density (``*_pdf``) and inverse (``*_to_square``).

Names, argument order and point conventions follow Mitsuba 3's ``mi.warp``:
the same ``u`` gives the same point. Densities are per unit area on planar
domains and per steradian on directions, and 0 off the support.
"""

from ._core.warp import (
    cosine_hemisphere_to_square,
    cosine_power_hemisphere_to_square,
    interval_to_power,
    interval_to_power_pdf,
    power_to_interval,
    square_to_cosine_hemisphere,
    square_to_cosine_hemisphere_pdf,
    square_to_cosine_power_hemisphere,
    square_to_cosine_power_hemisphere_pdf,
    square_to_uniform_cone,
    square_to_uniform_cone_pdf,
    square_to_uniform_disk,
    square_to_uniform_disk_concentric,
    square_to_uniform_disk_concentric_pdf,
    square_to_uniform_disk_pdf,
    square_to_uniform_hemisphere,
    square_to_uniform_hemisphere_pdf,
    square_to_uniform_sphere,
    square_to_uniform_sphere_pdf,
    square_to_uniform_triangle,
    square_to_uniform_triangle_pdf,
    uniform_cone_to_square,
    uniform_disk_to_square,
    uniform_disk_to_square_concentric,
    uniform_hemisphere_to_square,
    uniform_sphere_to_square,
    uniform_triangle_to_square,
)

__all__ = [
    "cosine_hemisphere_to_square",
    "cosine_power_hemisphere_to_square",
    "interval_to_power",
    "interval_to_power_pdf",
    "power_to_interval",
    "square_to_cosine_hemisphere",
    "square_to_cosine_hemisphere_pdf",
    "square_to_cosine_power_hemisphere",
    "square_to_cosine_power_hemisphere_pdf",
    "square_to_uniform_cone",
    "square_to_uniform_cone_pdf",
    "square_to_uniform_disk",
    "square_to_uniform_disk_concentric",
    "square_to_uniform_disk_concentric_pdf",
    "square_to_uniform_disk_pdf",
    "square_to_uniform_hemisphere",
    "square_to_uniform_hemisphere_pdf",
    "square_to_uniform_sphere",
    "square_to_uniform_sphere_pdf",
    "square_to_uniform_triangle",
    "square_to_uniform_triangle_pdf",
    "uniform_cone_to_square",
    "uniform_disk_to_square",
    "uniform_disk_to_square_concentric",
    "uniform_hemisphere_to_square",
    "uniform_sphere_to_square",
    "uniform_triangle_to_square",
]
