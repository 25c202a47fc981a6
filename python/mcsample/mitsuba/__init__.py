"""Interop with Mitsuba 3, in four parts:

- :mod:`.variant`: a variant that works here (``llvm_ad_rgb`` when a
  libLLVM >= 16 runs, proven in a subprocess, else ``scalar_rgb``);
- :mod:`.phong`: mcsample's Phong BRDF as the Mitsuba BSDF plugin
  ``"mcsample_phong"``, written in Dr.Jit independently of the Rust one;
- :mod:`.export` and :mod:`.reference`: an :class:`mcsample.Scene` as a
  Mitsuba scene dict, and reference renders with per-pixel variances;
- :mod:`.emitters`: Mitsuba's envmap emitter next to an
  :class:`mcsample.EnvMap`.
"""

from .emitters import (MitsubaEmitterSample, emitter_eval, emitter_pdf, emitter_sample, envmap_dict,
                       envmap_emitter)
from .export import scene_dict
from .phong import register_phong
from .reference import render_reference, render_runs
from .variant import (MIN_LLVM, available, choose_variant, find_libllvm, llvm_usable, load,
                      variant_set)

__all__ = ["MIN_LLVM", "MitsubaEmitterSample", "available", "choose_variant", "emitter_eval",
           "emitter_pdf", "emitter_sample", "envmap_dict", "envmap_emitter", "find_libllvm",
           "llvm_usable", "load", "register_phong", "render_reference", "render_runs",
           "scene_dict",
           "variant_set"]
