"""The Mitsuba 3 reference renderer for course scenes: translator, custom plugins, CLI.

Importing the package loads Mitsuba (with a usable libLLVM pinned), sets the default variant
`llvm_ad_rgb` unless one of ours is already set, and registers the plugins `course_camera`
(sensor), `course_phong` (BSDF) and `course_whitted` (integrator) for it;
`mitsuba_ref.variant.use("cuda_ad_rgb")` switches variant. If Mitsuba cannot be loaded here (no
usable libLLVM), the import still succeeds and the first render reports why, in one line.
"""
from . import variant

try:
    variant.ensure()
except variant.VariantError:
    pass  # raised again, as a one-line error, by variant.use() when something is rendered
