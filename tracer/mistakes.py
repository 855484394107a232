"""The catalogue of mistakes: what a student's program can get wrong in each function of the
assignment's starter code, each a switch of the tracer's course mode (arithmetic/mistaken.py)
that renders the reference *with that mistake*, so that an image the mistaken reference
reproduces names its cause (the harness's cause search, harness/judge/causes.py).

One entry per mistake: its code, the starter-code function it lives in, what the program does,
and where it has one, its parameter (a number the program got wrong: an offset, an exponent, a
threshold) with the values a search tries first. A render switches mistakes on with
`Switch(code, value)`, spelled `code` or `code=value` on the command line
(`python -m raycheck.tracer --mistake shadow_offset=0.1`). MISTAKES holds the catalogue's
hand-written entries and those operators.py generates at the sites of the course's formulas
(`--mistake ndc_x_scale.constant=3`).

    switch = parse_switch("falloff_power=1")     # Switch("falloff_power", 1.0)
    MISTAKES["falloff_power"].function          # "PointLight::getIllumination"
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from .mistake_model import COLOR, HITS, NORMALS, OFFSET, Family, Mistake, Needs, Parameter
from .operators import GENERATED, GENERATED_CODES

if TYPE_CHECKING:
    from .scene.model import Scene
    from .scene.request import RenderRequest


class Code(StrEnum):
    """Every mistake's code, once: the catalogue's entries, their hooks (hooks() below), the
    request rewrites and the searches name mistakes by these members, so that a misspelt code
    is an AttributeError, not the course's value computed silently."""

    FALLOFF_POWER = "falloff_power"
    FALLOFF_IGNORED = "falloff_ignored"
    LIGHT_REVERSED = "light_reversed"
    LIGHT_UNNORMALISED = "light_unnormalised"
    SPECULAR_HALF_VECTOR = "specular_half_vector"
    SPECULAR_REVERSED = "specular_reversed"
    SPECULAR_GATED = "specular_gated"
    SHININESS_SCALE = "shininess_scale"
    DIFFUSE_UNCLAMPED = "diffuse_unclamped"
    AMBIENT_PER_LIGHT = "ambient_per_light"
    AMBIENT_PER_LIT_LIGHT = "ambient_per_lit_light"
    LIGHTS_SKIPPED = "lights_skipped"
    SHADOW_MISSING = "shadow_missing"
    SHADOW_INVERTED = "shadow_inverted"
    SHADOW_ALWAYS = "shadow_always"
    SHADOW_OFFSET = "shadow_offset"
    SHADOW_OFFSET_NORMAL = "shadow_offset_normal"
    SHADOW_BEYOND_LIGHT = "shadow_beyond_light"
    SHADOW_DISTANCE_SQUARED = "shadow_distance_squared"
    REFLECTION_OFFSET = "reflection_offset"
    REFLECTION_OFFSET_NORMAL = "reflection_offset_normal"
    REFLECTION_GATE = "reflection_gate"
    REFLECTION_PER_LIGHT = "reflection_per_light"
    REFLECTION_PER_LIT_LIGHT = "reflection_per_lit_light"
    REFLECTION_UNWEIGHTED = "reflection_unweighted"
    REFLECTION_WEIGHT_SQUARED = "reflection_weight_squared"
    REFLECTION_DEPTH = "reflection_depth"
    TRIANGLE_FLAT_NORMALS = "triangle_flat_normals"
    TRIANGLE_NORMAL_ONE_VERTEX = "triangle_normal_one_vertex"
    TRIANGLE_NORMAL_WEIGHTS = "triangle_normal_weights"
    TRIANGLE_NORMAL_UNNORMALISED = "triangle_normal_unnormalised"
    TRANSFORM_NORMAL_OBJECT = "transform_normal_object"
    TRANSFORM_NORMAL_UNNORMALISED = "transform_normal_unnormalised"
    TRANSFORM_DIRECTION_NORMALISED = "transform_direction_normalised"
    PLANE_OFFSET_NEGATED = "plane_offset_negated"
    PLANE_NORMALISED = "plane_normalised"
    PLANE_SHADING_NORMAL_NORMALISED = "plane_shading_normal_normalised"
    SPHERE_FAR_ROOT = "sphere_far_root"
    SPHERE_INSIDE_MISSED = "sphere_inside_missed"
    NDC_PIXEL_CENTRE = "ndc_pixel_centre"
    NDC_HALF_SHIFT = "ndc_half_shift"
    FILTER_IGNORED = "filter_ignored"
    JITTER_FIXED = "jitter_fixed"
    JITTER_CENTRED = "jitter_centred"
    JITTER_SAMPLES = "jitter_samples"
    JITTER_AUX_ONE_SAMPLE = "jitter_aux_one_sample"


def _m(code: Code, family: Family, function: str, does: str, needs: set[Needs],
       kinds: frozenset[str] = COLOR, parameter: Parameter | None = None) -> Mistake:
    return Mistake(code, family, function, does, frozenset(needs), kinds, parameter)


L, S, SH, R, G, C = (Family.LIGHTS, Family.SHADING, Family.SHADOWS, Family.REFLECTION,
                     Family.GEOMETRY, Family.CAMERA)
ILLUMINATION = "PointLight::getIllumination"
SHADE = "Material::shade"
TRACE = "Renderer::traceRay"
CATALOGUE: tuple[Mistake, ...] = (
    # --- lights
    _m(Code.FALLOFF_POWER, L, ILLUMINATION,
       "divides a point light's color by falloff * d^{value} instead of falloff * d^2",
       {Needs.POINT_LIGHT}, parameter=Parameter("exponent", 2.0, (0.0, 1.0, 3.0), 0.0, 4.0)),
    _m(Code.FALLOFF_IGNORED, L, ILLUMINATION,
       "gives a point light its full color at every distance (no falloff * d^2 division)",
       {Needs.POINT_LIGHT}),
    _m(Code.LIGHT_REVERSED, L, ILLUMINATION,
       "returns the direction from the light to the point (L reversed): a directional "
       "light's direction itself, or p - position", {Needs.LIGHT}),
    _m(Code.LIGHT_UNNORMALISED, L, ILLUMINATION,
       "returns position - p without normalising it", {Needs.POINT_LIGHT}),
    # --- shading
    _m(Code.SPECULAR_HALF_VECTOR, S, SHADE,
       "raises N.H (Blinn's half vector) to the shininess instead of R.L",
       {Needs.LIGHT, Needs.SPECULAR}),
    _m(Code.SPECULAR_REVERSED, S, SHADE,
       "mirrors the wrong vector for the highlight (R from L with the eye direction E, or the "
       "eye ray reflected with -E): its cosine has the opposite sign",
       {Needs.LIGHT, Needs.SPECULAR}),
    _m(Code.SPECULAR_GATED, S, SHADE,
       "adds the specular term only where N.L > 0 (the course adds it wherever R.L > 0)",
       {Needs.LIGHT, Needs.SPECULAR}),
    _m(Code.SHININESS_SCALE, S, SHADE,
       "raises the cosine to {value} x the shininess", {Needs.LIGHT, Needs.SPECULAR},
       parameter=Parameter("factor", 1.0, (0.0, 0.5, 2.0), 0.0, 8.0)),
    _m(Code.DIFFUSE_UNCLAMPED, S, SHADE,
       "does not clamp N.L at 0: lights behind a surface darken it", {Needs.LIGHT}),
    # without lights these add no ambient term at all: they show in every scene
    _m(Code.AMBIENT_PER_LIGHT, S, SHADE,
       "adds the ambient term once per light instead of once", set()),
    _m(Code.AMBIENT_PER_LIT_LIGHT, S, SHADE,
       "adds the ambient term inside the light loop: once per light that is not shadowed",
       set()),
    _m(Code.LIGHTS_SKIPPED, L, TRACE,
       "adds no light's term: the loop over the lights does not run (only the ambient term "
       "and the mirrors' reflections remain)", {Needs.LIGHT}),
    # --- shadows
    _m(Code.SHADOW_MISSING, SH, TRACE, "casts no shadow rays", {Needs.SHADOWS, Needs.LIGHT}),
    _m(Code.SHADOW_INVERTED, SH, TRACE,
       "negates the shadow test: a point counts as shadowed where its shadow ray hits nothing "
       "and as lit where it is blocked", {Needs.SHADOWS, Needs.LIGHT}),
    _m(Code.SHADOW_ALWAYS, SH, TRACE,
       "counts every shadow ray as blocked: with -shadows only the ambient term and the "
       "mirrors' reflections remain", {Needs.SHADOWS, Needs.LIGHT}),
    # a tmin of eps on a ray from p is the same test as an origin p + eps * L (but for blockers
    # within eps of the light): one entry
    _m(Code.SHADOW_OFFSET, SH, TRACE,
       "starts shadow rays at p + {value} * L, or ignores blockers closer than t = {value} "
       "(the course: p + 0.01 * L)",
       {Needs.SHADOWS, Needs.LIGHT}, parameter=OFFSET),
    _m(Code.SHADOW_OFFSET_NORMAL, SH, TRACE,
       "starts shadow rays at p + {value} * N (along the normal, not along L)",
       {Needs.SHADOWS, Needs.LIGHT},
       parameter=Parameter("offset", None, (1e-4, 1e-3, 0.01, 0.05, 0.1), 0.0, 1.0,
                           geometric=True)),
    _m(Code.SHADOW_BEYOND_LIGHT, SH, TRACE,
       "lets blockers beyond a point light shadow it (the shadow ray's hit is not compared "
       "with the light's distance)", {Needs.SHADOWS, Needs.POINT_LIGHT}),
    _m(Code.SHADOW_DISTANCE_SQUARED, SH, TRACE,
       "compares the blocker's t with the squared distance to the point light",
       {Needs.SHADOWS, Needs.POINT_LIGHT}),
    # --- reflection
    _m(Code.REFLECTION_OFFSET, R, TRACE,
       "starts reflected rays at p + {value} * R (the course: p + 0.01 * R)",
       {Needs.BOUNCES, Needs.SPECULAR}, parameter=OFFSET),
    _m(Code.REFLECTION_OFFSET_NORMAL, R, TRACE,
       "starts reflected rays at p + {value} * N (along the normal, not along R)",
       {Needs.BOUNCES, Needs.SPECULAR},
       parameter=Parameter("offset", None, (1e-4, 1e-3, 0.01, 0.05, 0.1), 0.0, 1.0,
                           geometric=True)),
    _m(Code.REFLECTION_GATE, R, TRACE,
       "mirrors materials with |ks| > {value} (the course: |ks| > 0.1, by its Euclidean "
       "length)", {Needs.BOUNCES, Needs.SPECULAR},
       parameter=Parameter("threshold", 0.1, (0.0, 0.3, 0.5, 1.0, 1.1), 0.0, 1.8)),
    _m(Code.REFLECTION_PER_LIGHT, R, TRACE,
       "adds the reflection inside the light loop: once per light", {Needs.BOUNCES,
                                                                      Needs.SPECULAR}),
    _m(Code.REFLECTION_PER_LIT_LIGHT, R, TRACE,
       "adds the reflection inside the light loop: once per light that is not shadowed",
       {Needs.BOUNCES, Needs.SPECULAR}),
    _m(Code.REFLECTION_UNWEIGHTED, R, TRACE,
       "adds the reflected color without multiplying it by ks", {Needs.BOUNCES,
                                                                  Needs.SPECULAR}),
    _m(Code.REFLECTION_WEIGHT_SQUARED, R, TRACE,
       "multiplies the reflected color by ks twice", {Needs.BOUNCES, Needs.SPECULAR}),
    _m(Code.REFLECTION_DEPTH, R, TRACE,
       "follows {value} mirror bounce(s) more than -bounces asks for (negative: fewer)",
       {Needs.SPECULAR},
       parameter=Parameter("extra bounces", 0.0, (-1.0, 1.0), -4.0, 4.0, integer=True)),
    # --- geometry
    _m(Code.TRIANGLE_FLAT_NORMALS, G, "Triangle::intersect",
       "shades triangles with their face normal, not the interpolated vertex normals",
       {Needs.TRIANGLE}, NORMALS),
    _m(Code.TRIANGLE_NORMAL_ONE_VERTEX, G, "Triangle::intersect",
       "uses vertex0's normal for the whole triangle", {Needs.TRIANGLE}, NORMALS),
    _m(Code.TRIANGLE_NORMAL_WEIGHTS, G, "Triangle::intersect",
       "interpolates the vertex normals with the barycentric weights in the wrong order "
       "(alpha on n1, beta on n2, gamma on n0)", {Needs.TRIANGLE}, NORMALS),
    _m(Code.TRIANGLE_NORMAL_UNNORMALISED, G, "Triangle::intersect",
       "does not normalise the interpolated normal", {Needs.TRIANGLE}, NORMALS),
    _m(Code.TRANSFORM_NORMAL_OBJECT, G, "Transform::intersect",
       "returns the hit normal in the object's space (not transformed to the world)",
       {Needs.TRANSFORM}, NORMALS),
    _m(Code.TRANSFORM_NORMAL_UNNORMALISED, G, "Transform::intersect",
       "does not normalise the normal after transforming it", {Needs.TRANSFORM}, NORMALS),
    _m(Code.TRANSFORM_DIRECTION_NORMALISED, G, "Transform::intersect",
       "normalises the ray's direction in object space, so t is measured in the object's "
       "units, not the world's", {Needs.TRANSFORM}, HITS),
    _m(Code.PLANE_OFFSET_NEGATED, G, "Plane::intersect",
       "takes the plane as n.p = -offset", {Needs.PLANE}, HITS),
    _m(Code.PLANE_NORMALISED, G, "Plane::Plane",
       "normalises the plane's normal and keeps its offset (the plane moves where |n| != 1)",
       {Needs.PLANE}, HITS),
    _m(Code.PLANE_SHADING_NORMAL_NORMALISED, G, "Plane::intersect",
       "normalises the normal it returns (the course returns the scene's raw normal)",
       {Needs.PLANE}, NORMALS),
    _m(Code.SPHERE_FAR_ROOT, G, "Sphere::intersect",
       "takes the farther root where both are in front of the ray", {Needs.SPHERE}, HITS),
    _m(Code.SPHERE_INSIDE_MISSED, G, "Sphere::intersect",
       "misses a sphere from inside (only the nearer root counts)", {Needs.SPHERE}, HITS),
    # --- camera
    _m(Code.NDC_PIXEL_CENTRE, C, "Renderer::Render",
       "maps pixel x to 2*(x+0.5)/w - 1 (the course: 2*x/(w-1) - 1)", set(), HITS),
    _m(Code.NDC_HALF_SHIFT, C, "Renderer::Render",
       "maps pixel x to 2*(x+0.5)/(w-1) - 1: the image moves by half a pixel", set(), HITS),
    # the one mistake that changes the kernel's structure (the rays a pixel): RenderOptions
    # renders it as the request without -filter
    _m(Code.FILTER_IGNORED, C, "Renderer::Render",
       "ignores -filter (one ray a pixel, no 3x3 filter)", {Needs.FILTER}, HITS),
    # --- -jitter: where the samples fall and how many are averaged. A jittered image is one
    # draw of a distribution: the harness judges these by the distribution the mistaken
    # reference draws from (harness/diagnosis/jitter_causes.py)
    _m(Code.JITTER_FIXED, C, "Renderer::Render",
       "puts every -jitter sample at the same place, x + {value} (no random offset; the "
       "course: x + a random number in [0, 1))", {Needs.JITTER}, HITS,
       Parameter("offset", None, (0.0, 0.5), 0.0, 1.0)),
    _m(Code.JITTER_CENTRED, C, "Renderer::Render",
       "draws -jitter offsets from a window {value} (sub-)pixel(s) wide centred on x (the "
       "course: [x, x + 1))", {Needs.JITTER}, HITS,
       Parameter("width", None, (1.0, 2.0), 0.0, 4.0)),
    _m(Code.JITTER_SAMPLES, C, "Renderer::Render",
       "averages {value} -jitter samples a (sub-)pixel (the course: 16)", {Needs.JITTER}, HITS,
       Parameter("samples", 16.0, (1.0, 2.0, 4.0, 8.0), 1.0, 64.0, integer=True)),
    _m(Code.JITTER_AUX_ONE_SAMPLE, C, "Renderer::Render",
       "writes one -jitter sample's normal and depth, not the mean of the samples",
       {Needs.JITTER}, frozenset({"normals", "depth"})),
)
# the mistakes that change how a jittered image's samples are drawn: only a jittered case can
# show them, and only its distribution can tell them
JITTER_MISTAKES = frozenset(m.code for m in CATALOGUE if Needs.JITTER in m.needs)
# keyed by the Code members and the generated codes, looked up by any spelling too (a StrEnum
# member hashes and compares as its string): a switch's code or the command line's text
MISTAKES: dict[str, Mistake] = {m.code: m for m in CATALOGUE + GENERATED}
# the module whose hook computes each mistake, as hooks() registers them at import
HOOKED: dict[str, str] = {}


def hooks(module: str, *codes: str) -> frozenset[str]:
    """A module's declaration of the mistakes its hooks compute, made at import: each code in
    one module only (tests/tracer/test_mistakes.py: every entry has its hook, and a module's
    hooks name only the codes it declares). A code is a Code member or a generated mistake's
    (operators.site_codes)."""
    for code in codes:
        if not isinstance(code, Code) and code not in GENERATED_CODES:
            raise TypeError(f"{module}: {code!r} is not a mistake's Code")
        if HOOKED.setdefault(code, module) != module:
            raise ValueError(f"mistake {code} is hooked in {HOOKED[code]} and in {module}")
    return frozenset(codes)


@dataclass(frozen=True, order=True)
class Switch:
    """A mistake switched on, with its parameter's value (None for one without)."""

    code: str
    value: float | None = None

    @property
    def mistake(self) -> Mistake:
        return MISTAKES[self.code]

    def __str__(self) -> str:
        return self.code if self.value is None else f"{self.code}={self.value:g}"

    @property
    def exact(self) -> str:
        """`code` or `code=value` with every digit of the value: parse_switch reads back the
        same switch."""
        return self.code if self.value is None else f"{self.code}={self.value!r}"

    def describe(self) -> str:
        return self.mistake.describe(self.value)


class MistakeError(ValueError):
    """A mistake the catalogue does not have, or a bad parameter (the message says which)."""


def parse_switch(text: str) -> Switch:
    """`code` or `code=value` as a Switch, checked against the catalogue."""
    code, eq, value = text.partition("=")
    mistake = MISTAKES.get(code.strip())
    if mistake is None:
        raise MistakeError(f"unknown mistake {code.strip()!r} (known: "
                           f"{', '.join(MISTAKES)})")
    if not eq:
        if mistake.parameter is not None:
            raise MistakeError(f"mistake {mistake.code} needs its {mistake.parameter.name}: "
                               f"{mistake.code}=VALUE")
        return Switch(mistake.code)
    if mistake.parameter is None:
        raise MistakeError(f"mistake {mistake.code} has no parameter")
    try:
        number = float(value)
    except ValueError:
        raise MistakeError(f"mistake {mistake.code}: {value!r} is not a number") from None
    return check_switch(Switch(mistake.code, number))


def check_switch(switch: Switch) -> Switch:
    """The switch, if its code is known and its value within its parameter's range."""
    mistake = MISTAKES.get(switch.code)
    if mistake is None:
        raise MistakeError(f"unknown mistake {switch.code!r}")
    p = mistake.parameter
    if p is None:
        if switch.value is not None:
            raise MistakeError(f"mistake {switch.code} has no parameter")
        return switch
    if switch.value is None or not p.low <= switch.value <= p.high:
        raise MistakeError(f"mistake {switch.code}: its {p.name} must be in "
                           f"[{p.low:g}, {p.high:g}]")
    if p.integer and switch.value != int(switch.value):
        raise MistakeError(f"mistake {switch.code}: its {p.name} must be a whole number")
    return switch


def switches(items) -> tuple[Switch, ...]:
    """Switches (or their spellings) checked, one per code, in a canonical order."""
    out = [parse_switch(s) if isinstance(s, str) else check_switch(s) for s in items]
    codes = [s.code for s in out]
    repeated = sorted({c for c in codes if codes.count(c) > 1})
    if repeated:
        raise MistakeError(f"mistake {repeated[0]} given twice")
    return tuple(sorted(out))


def present(scene: Scene, request: RenderRequest) -> frozenset[Needs]:
    """What of Needs a scene rendered with a request has: the mistakes whose needs are all
    present can change its images."""
    from .scene.model import DirectionalLight, Mesh, Plane, PointLight, Sphere, Triangle, primitives

    have: set[Needs] = set()
    if scene.lights:
        have.add(Needs.LIGHT)
    if any(isinstance(light, PointLight) for light in scene.lights):
        have.add(Needs.POINT_LIGHT)
    if any(isinstance(light, DirectionalLight) for light in scene.lights):
        have.add(Needs.DIRECTIONAL_LIGHT)
    if request.shadows:
        have.add(Needs.SHADOWS)
    if request.bounces:
        have.add(Needs.BOUNCES)
    if request.filter:
        have.add(Needs.FILTER)
    if request.jitter:
        have.add(Needs.JITTER)
    if any(any(m.specular) for m in scene.materials):
        have.add(Needs.SPECULAR)
    kinds = {Sphere: Needs.SPHERE, Plane: Needs.PLANE, Triangle: Needs.TRIANGLE,
             Mesh: Needs.TRIANGLE}
    for obj, transforms in primitives(scene.root):
        have.add(kinds[type(obj)])
        if transforms:
            have.add(Needs.TRANSFORM)
    return frozenset(have)


def applicable(scene: Scene, request: RenderRequest,
               among: tuple[Mistake, ...] = CATALOGUE) -> tuple[Mistake, ...]:
    """The mistakes (of the catalogue, or `among`: operators.GENERATED) that can change this
    render's images."""
    have = present(scene, request)
    return tuple(m for m in among if m.needs <= have)
