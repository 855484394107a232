"""Where to look when no known mistake reproduces a failing image: the starter function whose
work differs, read off what differs and what does not (a contrast), as a `located` finding.

Each rule follows from what the starter's functions compute, not from any program's bugs:
* a difference that goes away with a flag turned off lives in that flag's code. -jitter and
  -filter are Renderer::Render's alone, once the rays they place are accounted for: without
  them the case is rendered at three times the size, where a geometry bug that one ray a pixel
  misses shows too; where that render differs, it is read as a case of one ray a pixel
  (OneRay) by the rules below. -bounces is the mirror recursion of Renderer::traceRay,
  -shadows its shadow test with the distance PointLight::getIllumination hands it; both trace
  rays that start on a surface, which the intersect functions may treat differently. A
  color image that matches the reference's rendered with -shadows or -bounces, which the case
  does not ask for, is that flag's gate in Renderer::traceRay, run unasked;
* a difference of the geometry (the normals or depth image) confined to the objects of one
  primitive type, while objects of another type are in view and match, is that type's
  intersect (a mesh's faces are triangles); confined to transformed objects while untransformed
  ones match, it is Transform::intersect. Where the scene holds objects of one intersect
  alone, it is that intersect, the primary rays or (every one of them transformed) the
  Transform: a list, which the program's other cases may narrow (cross_case.py); so too,
  with the Transform where any is transformed, wherever the difference lies;
* an image asked for and not written by a program that exits with status 0 is the saving at
  the end of Renderer::Render (the starter's parser is the reference's: a scene the
  reference renders parses); so is a non-zero exit status after some of the images are
  written (an exit the program chose: a crash there may be damage done anywhere before);
* images that differ only where they are black on whole rows or columns, the normals among
  them: pixels never written, by the pixel loop of Renderer::Render or the loop that copies
  its values into the images (a written pixel's normals are (n + 1)/2 of a hit's unit normal,
  some channel above 0, or a miss's 0.5); images that are, wherever the read is defined, the
  reference's pixels read from elsewhere in its buffer: Renderer::Render's too (whole pixels
  moved: an index, the -filter path taken without -filter);
* a color image whose geometry matches: every pixel differs, background too, is the pixel loop
  of Renderer::Render (traceRay returns the background before any shading); only the
  background, traceRay's miss; elsewhere the shading, which several functions share.
A finding names one function (its message starts `Class::function:`) only where the contrast
leaves one; otherwise it lists those that remain. Thresholds are calibrated on the mutation
benchmark's tuning sample (docs/findings.md gives each rule's precision).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from raycheck.tracer.operators import K
from raycheck.tracer.pixel_index import OUTPUT_FORMS, TAP_FORMS, output_read, taps_read
from raycheck.tracer.scene.model import PointLight, Scene
from raycheck.tracer.shade.auxiliary import scene_objects

from ..cases import Case
from ..judge import findings, thresholds
from ..judge.findings import Finding, as_bytes, differs, mask_image
from ..judge.parts import Parts
from ..judge.verdict import KindVerdict, as_values
from ..records import FindingRecord, Role, Verdict

# the starter function whose intersect draws each object kind of the object image
INTERSECT = {"sphere": "Sphere::intersect", "plane": "Plane::intersect",
             "triangle": "Triangle::intersect", "mesh": "Triangle::intersect"}
PLURAL = {"sphere": "spheres", "plane": "planes", "triangle": "triangles", "mesh": "meshes"}
TRANSFORM = "Transform::intersect"
RENDER = "Renderer::Render"
TRACE = "Renderer::traceRay"
# Of the differing pixels, the share within reach of the suspected objects that confines the
# difference to them (silhouette pixels where an object grew fall on its neighbours), and the
# share on them (a grown object's ring may not outnumber what changed on the object itself:
# else the object behind, whose silhouette the ring also touches, is as suspect).
CONFINED_SHARE = 0.9
OWN_SHARE = 0.5
# The reach: pixels this far (in pixels) from a suspected object count as its silhouette's.
REACH = 2
# An object kind is in view for a contrast when this share of the image (at least
# CONTRAST_PIXELS pixels) shows it, outside the suspected objects' reach.
CONTRAST_SHARE = 0.02
CONTRAST_PIXELS = 20
# ... and match there: at most this share of those pixels differ
CONTRAST_CHANGED = 0.05
# "every pixel differs": this share of both the background's and the objects' pixels
EVERYWHERE_SHARE = 0.9
# pixels moved: the share of the image whose read from the buffer is defined
READ_DEFINED = 0.1
NO_IMAGE = "your program gives no image of this case"  # the lead where a program gives none
GEOMETRY_KINDS = ("normals", "depth")


@dataclass(frozen=True)
class OneRay:
    """The images localise reads past the flags, of one ray a pixel, judged, with the
    reference's parts of them: a case's own, or a -jitter or -filter case's rendered without
    them at `scale` times its size, where rays at the sub-pixel positions show what a geometry
    bug does between pixel centres (`said`: so rendered, in words)."""

    kinds: list[KindVerdict]
    images: dict[Role, dict[str, np.ndarray]]
    parts: Parts | None
    scale: int = 1
    said: str = ""


@dataclass(frozen=True)
class Located:
    """The functions a rule leaves (one: named) and the evidence it read."""

    functions: tuple[str, ...]
    evidence: str
    mask: np.ndarray | None = None  # the differing pixels, for the picture

    def finding(self, lead: str = "no known mistake reproduces this image") -> Finding:
        picture = None if self.mask is None else mask_image(self.mask)
        if len(self.functions) == 1:
            return Finding("located", f"{self.functions[0]}: {lead}; the evidence points "
                           f"here: {self.evidence}", picture, functions=self.functions)
        return Finding("located", f"{lead}; look at {either(self.functions)}: "
                       f"{self.evidence}", picture, functions=self.functions)


def either(functions: tuple[str, ...]) -> str:
    return f"{', '.join(functions[:-1])} or {functions[-1]}"


def narrowed(finding: FindingRecord, function: str, why: str) -> FindingRecord:
    """A located finding that leaves several functions (Located.finding's words) naming one
    of them, with why the others are left out."""
    lead, _, evidence = finding.message.partition(f"; look at {either(finding.functions or ())}: ")
    return FindingRecord("located", f"{function}: {lead}; the evidence points here: "
                         f"{evidence}; {why}", (function,))


def unwritten(kind: str = "", written: tuple[str, ...] = ()) -> Located:
    """Where a program that exits with status 0 without writing the image of `kind` asked for
    (having written `written`), or any image (no `kind`), is wrong: the images are saved at
    the end of the starter's Renderer::Render, after its pixel loop."""
    if kind and written:
        what = (f"it exits with status 0 having written its {' and '.join(written)} "
                f"image{'s' if len(written) > 1 else ''} but not its {kind} image")
    elif kind:
        what = f"it exits with status 0 without writing its {kind} image"
    else:
        what = ("it exits with status 0 without writing an image (a course program does so "
                "where its parser rejects the scene, which the reference's parsed)")
    return Located((RENDER,), f"{what}; the starter's Renderer::Render saves each image "
                   "asked for after its pixel loop")


def failed_saving(message: str, written: tuple[str, ...]) -> Located:
    """Where a program that exits with a non-zero status (`message`: "exited with status 1")
    having written the images of `written` is wrong: the starter's Renderer::Render saves
    the images at its end, and after that only main's return runs, the starter's."""
    kinds = " and ".join(filter(None, (", ".join(written[:-1]), written[-1])))
    images = f"image{'s' if len(written) > 1 else ''}"
    return Located((RENDER,), f"it {message} having written its {kinds} {images}; the "
                   "starter's Renderer::Render saves each image asked for "
                   "after its pixel loop, and nothing but the starter's code runs after it")


def shows_nothing(images: dict[Role, dict[str, np.ndarray]], parts: Parts) -> Located | None:
    """Where the candidate's images of a case show nothing but the background while the
    reference's show objects: every primary ray misses. A camera that looks away (the pixel
    loop of Renderer::Render), a traceRay that does not find the hit, intersects that never
    hit: each makes every ray miss and gives these very images, so a mistake that reproduces
    them does not tell which (a list; a cause that reproduces them follows it). Read where
    the background is one color, as it is where the reference's background pixels are."""
    hit = parts.images["object"] >= 0
    got = images[Role.CANDIDATE]
    if "color" not in got or not hit.any() or hit.all():
        return None
    color = as_bytes(got["color"])
    if color.shape[:2] != hit.shape:
        return None
    sky = as_bytes(images[Role.REFERENCE]["color"])[~hit] if "color" in images[Role.REFERENCE] \
        else as_bytes(parts.color)[~hit]
    flat = color.reshape(-1, color.shape[-1])
    if (flat != flat[0]).any() or (sky != flat[0]).any():
        return None
    # the geometry images asked for show one value too (a miss's normal and depth)
    if any((as_bytes(got[k]) != as_bytes(got[k]).reshape(-1, 3)[0]).any()
           for k in GEOMETRY_KINDS if k in got):
        return None
    return Located((RENDER, TRACE, *intersects(parts.scene)), (
        f"your images show nothing but the background, where the reference's show objects "
        f"on {int(hit.sum())} pixels: every primary ray misses, as it does where the camera "
        "looks away, where traceRay does not find the hit and where every intersect misses"))


def follows_flag(kind: str, flags: list[str],
                 off: dict[str, tuple[np.ndarray | None, np.ndarray | None]],
                 scene: Scene, pixels: int, failed: str = "") -> Located | None:
    """The first of the case's flags with which the difference goes: turned off, the
    candidate's image of the kind matches the reference's. off: flag -> (reference's,
    candidate's) images without it (None where a render failed); pixels: the case's image's;
    failed: what the program does with the flag where it gives no image ("is killed by
    signal SIGSEGV"), else its image of the kind differs."""
    for flag in flags:
        ref_off, got_off = off.get(flag, (None, None))
        # as many differing pixels as the verdict allows the case's image, however many the
        # render has: nine differing sub-pixels can change nine pixels of a -filter image
        if ref_off is None or got_off is None or ref_off.shape != got_off.shape or \
                differs(ref_off, got_off).sum() > thresholds.FAIL_SHARE * pixels:
            continue
        # where the program failed, every kind is checked (crash_located)
        only, matches = (f"your program {failed} only with {flag}", "its images match") \
            if failed else (f"your {kind} image differs only with {flag}",
                            f"its {kind} image matches")
        if flag in ("-jitter", "-filter"):
            return Located((RENDER,), f"{only}: rendered without it at three times the size "
                           f"(one ray at each sub-pixel position), {matches} the reference's; "
                           "what differs is how the samples are placed, weighted or averaged")
        said = f"{only}: without it, {matches} the reference's; "
        if flag == "-bounces":
            return Located((TRACE, *intersects(scene)), said + "the mirror recursion, or how an "
                           "intersect treats a ray that starts on a surface")
        point = any(isinstance(light, PointLight) for light in scene.lights)
        lights = ("PointLight::getIllumination",) if point else ()
        return Located((TRACE, *lights, *intersects(scene)),
                       said + "the shadow test" + (", the light's distance it compares with"
                                                    if point else "") +
                       ", or how an intersect treats a ray that starts on a surface")
    return None


def runs_unasked(kind: str, on: dict[str, tuple[np.ndarray | None, np.ndarray]],
                 pixels: int) -> Located | None:
    """The first flag the case does not ask for whose code the program runs anyway: its image
    of the kind matches the reference's rendered with the flag (on: flag -> that image, None
    where the render failed, and the candidate's image of the case). The gate of -shadows and
    of -bounces is Renderer::traceRay's (whether to test a light's shadow ray, whether to
    follow the mirror ray)."""
    for flag, (ref_on, got) in on.items():
        if ref_on is None or ref_on.shape != got.shape or \
                differs(ref_on, got).sum() > thresholds.FAIL_SHARE * pixels:
            continue
        what = "the shadow test" if flag == "-shadows" else "the mirror recursion"
        return Located((TRACE,), f"your {kind} image matches the reference's rendered with "
                       f"{flag}, which this case does not ask for: {what} runs without it")
    return None


def intersects(scene: Scene) -> tuple[str, ...]:
    """The intersect functions the scene's objects go through."""
    objects = scene_objects(scene)
    found = sorted({INTERSECT[o.kind] for o in objects})
    return (*found, TRANSFORM) if any(o.transformed for o in objects) else tuple(found)


def case_scene(case: Case) -> Scene | None:
    from raycheck.tracer.scene import SceneError, load_scene
    try:
        return load_scene(case.scene.path)
    except (SceneError, OSError, ValueError):
        return None


def grown(mask: np.ndarray, reach: int) -> np.ndarray:
    """mask grown by `reach` pixels (a square neighbourhood)."""
    grown = mask.copy()
    h, w = mask.shape
    p = np.pad(mask, reach)
    for dy in range(2 * reach + 1):
        for dx in range(2 * reach + 1):
            grown |= p[dy:dy + h, dx:dx + w]
    return grown


@dataclass(frozen=True)
class Confinement:
    """How a difference lies about suspected objects: the shares of the differing pixels on
    them (in the reference), within REACH pixels of them, and the contrast: the pixels of the
    other objects in view beyond that reach."""

    own: float
    near: float
    contrast: int
    contrast_changed: float  # of the contrast's pixels, the share that differs

    @property
    def confined(self) -> bool:
        """The difference lies on the suspected objects and their silhouettes."""
        return self.own >= OWN_SHARE and self.near >= CONFINED_SHARE

    def holds(self, size: int) -> bool:
        """Confined, and the other objects in view match."""
        return self.confined and \
            self.contrast >= max(CONTRAST_PIXELS, CONTRAST_SHARE * size) and \
            self.contrast_changed <= CONTRAST_CHANGED


def confinement(changed: np.ndarray, suspect: np.ndarray, others: np.ndarray) -> Confinement:
    reach = grown(suspect, REACH)
    total = max(int(changed.sum()), 1)
    view = others & ~reach
    return Confinement(float((changed & suspect).sum() / total),
                       float((changed & reach).sum() / total), int(view.sum()),
                       float((changed & view).sum() / max(int(view.sum()), 1)))


def geometry_place(parts: Parts, changed: np.ndarray, kinds: str) -> Located | None:
    """A geometry difference confined to one object kind's intersect, or to transformed
    objects, by contrast with objects in view that match."""
    obj = parts.images["object"]
    if obj.shape != changed.shape or not changed.any():
        return None
    of_kind: dict[str, list[int]] = {}
    for info in parts.objects:
        of_kind.setdefault(INTERSECT[info.kind], []).append(info.index)
    moved = [o.index for o in parts.objects if o.transformed]
    still = [o.index for o in parts.objects if not o.transformed]
    hit = obj >= 0
    total = int(changed.sum())
    alone: Located | None = None  # confined to the only objects of the scene: no contrast
    for function, indices in of_kind.items():
        suspect = np.isin(obj, indices)
        found = confinement(changed, suspect, hit & ~suspect)
        if not found.holds(changed.size):
            # where the scene holds nothing else: another object, however small or out of
            # view, may have grown over these (a sphere that covers the planes behind it)
            if found.confined and len(of_kind) == 1:
                mine = [o for o in parts.objects if o.index in indices]
                moved_too = (TRANSFORM,) if all(o.transformed for o in mine) else ()
                alone = Located((function, RENDER, *moved_too), (
                    f"the {kinds} differ only on the "
                    f"{' and '.join(sorted({PLURAL[o.kind] for o in mine}))} "
                    f"({len(mine)} in the scene), the only objects in the scene: "
                    f"{found.own:.0%} of the {total} differing pixels on them, "
                    f"{found.near:.0%} within {REACH} pixels"), changed)
            continue
        mine = [o for o in parts.objects if o.index in indices]
        # a plane's normal is one vector and its depth nearly linear: planes alone in view
        # match under a primary ray a little off too (measured on the mutation benchmark's
        # tuning sample: a rescaled ndc, named Sphere::intersect against the floor)
        curved = np.isin(obj, [o.index for o in parts.objects
                               if o.kind != "plane" and o.index not in indices])
        if not confinement(changed, suspect, curved).holds(changed.size):
            function_or_rays: tuple[str, ...] = (function, RENDER)
        else:
            function_or_rays = (function,)
        shown = " and ".join(sorted({PLURAL[o.kind] for o in mine}))
        evidence = (f"the {kinds} differ only on the {shown} ({len(mine)} in the scene) and "
                    f"at their silhouettes: {found.own:.0%} of the {total} differing pixels on "
                    f"them, {found.near:.0%} within {REACH} pixels; the other objects match")
        if len(function_or_rays) > 1:
            evidence += " (only planes, which a primary ray a little off leaves as they are)"
        if all(o.transformed for o in mine):
            # Transform::intersect is ruled out only by other transformed objects that match
            others = np.isin(obj, [i for i in moved if i not in indices])
            if not confinement(changed, suspect, others).holds(changed.size):
                return Located((*function_or_rays, TRANSFORM), evidence + "; every one of "
                               "them is transformed", changed)
        return Located(function_or_rays, evidence, changed)
    if moved and still:
        suspect = np.isin(obj, moved)
        found = confinement(changed, suspect, np.isin(obj, still))
        if found.holds(changed.size):
            return Located((TRANSFORM,), f"the {kinds} differ only on the transformed objects "
                           f"({len(moved)} in the scene) and at their silhouettes: "
                           f"{found.own:.0%} of the "
                           f"{total} differing pixels on them; the {len(still)} untransformed "
                           "objects match", changed)
    return alone


def one_intersect(parts: Parts, changed: np.ndarray, kinds: str) -> Located | None:
    """A geometry difference, wherever it lies, in a scene all of whose objects go through
    one intersect: that intersect, the primary rays or (any of them transformed) the
    Transform: a list, which the program's other cases may narrow (an object grown over the
    background differs off the objects as much as on them)."""
    functions = {INTERSECT[o.kind] for o in parts.objects}
    if len(functions) != 1 or not changed.any():
        return None
    moved = (TRANSFORM,) if any(o.transformed for o in parts.objects) else ()
    hit = parts.images["object"] >= 0
    shown = " and ".join(sorted({PLURAL[o.kind] for o in parts.objects}))
    return Located((*functions, RENDER, *moved), (
        f"the {kinds} differ on {int(changed.sum())} pixels, {int((changed & ~hit).sum())} "
        f"of them where the reference shows the background; the scene holds {shown} alone "
        f"({len(parts.objects)}{', some transformed' if moved else ''})"), changed)


def whole_lines(changed: np.ndarray, kinds: str, objects: np.ndarray) -> Located | None:
    """Differences in whole rows or columns of the image, whatever they show: the pixel
    loop's (a loop bound, an index), Renderer::Render. A line counts where the reference
    shows more than one thing along it (objects: its object image, -1 the background): a
    row of background alone, above the horizon, is what a plane that covers it changes."""
    mixed_rows = (objects != objects[:, :1]).any(axis=1)
    mixed_cols = (objects != objects[:1, :]).any(axis=0)
    rows, cols = changed.all(axis=1) & mixed_rows, changed.all(axis=0) & mixed_cols
    lines = np.zeros_like(changed)
    lines[rows, :] = True
    lines[:, cols] = True
    total = int(changed.sum())
    # lines over most of the image are a difference everywhere (everywhere's)
    if not lines.any() or lines.mean() > 0.5 or (changed & lines).sum() < CONFINED_SHARE * total:
        return None
    return Located((RENDER,), f"the {kinds} differ in {int(rows.sum())} whole rows and "
                   f"{int(cols.sum())} whole columns of the image, whatever they show "
                   f"({(changed & lines).sum() / total:.0%} of the {total} differing "
                   "pixels): the pixel loop", changed)


def blank_lines(images: dict[Role, dict[str, np.ndarray]], said: str = "") -> Located | None:
    """Each of the images (normals among them) differing from the reference's only on whole
    rows or columns where it is black, within the verdict's tolerance: pixels nobody wrote
    (an image starts black; a loop left early may write one image of a pixel and not the
    next). No pixel the pixel loop writes has black normals: a unit normal's (n + 1)/2 has a
    channel above 0 and a miss's is 0.5; a NaN normal (a sphere hit at t = 10000) has a
    depth that is not black."""
    got, ref = images[Role.CANDIDATE], images[Role.REFERENCE]
    kinds = [k for k in ("color", *GEOMETRY_KINDS) if k in got and k in ref
             and as_bytes(got[k]).shape == as_bytes(ref[k]).shape]
    if "normals" not in kinds:
        return None
    unwritten = {}
    for k in kinds:
        mine = as_bytes(got[k])
        black = mine.max(axis=2) == 0
        rows, cols = black.all(axis=1), black.all(axis=0)
        lines = rows[:, None] | cols[None, :]
        changed = differs(as_bytes(ref[k]), mine)
        if (changed & ~lines).sum() > thresholds.FAIL_SHARE * changed.size:
            return None
        unwritten[k] = (int(rows.sum()), int(cols.sum()), changed & lines)
    rows, cols, normals = unwritten["normals"]
    if not normals.any():
        return None
    counted = [f"{n} whole {line}{'s' if n > 1 else ''}"
               for n, line in ((rows, "row"), (cols, "column")) if n]
    where = "every pixel" if normals.all() else " and ".join(counted)
    rendered = f" ({said})" if said else ""
    return Located((RENDER,), f"your {', '.join(kinds)} images{rendered} differ only where "
                   f"they are black on whole rows or columns, the normals on {where}, which "
                   "no written pixel is (a unit normal's (n + 1)/2 has a channel above 0, a "
                   "miss's is 0.5): pixels never written, by the pixel loop (its bounds, a "
                   "loop left early) or the loop that copies its values into the images",
                   np.logical_or.reduce([m for _, _, m in unwritten.values()]))


def read_elsewhere(images: dict[Role, dict[str, np.ndarray]], said: str = "") -> Located | None:
    """The images, wherever the read is defined, the reference's values read from another
    place of its buffer: at another index (pixel_index.py's one-operator forms of y * w + x),
    or filtered as -filter does from a buffer of the image's own size (the -filter path taken
    without -filter). The rest of the pixels read outside the buffer, which C leaves undefined
    (another array's values, garbage). Whole pixels moved are Renderer::Render's: no formula
    of the other functions moves a pixel. At least READ_DEFINED of the image must be defined,
    with CONTRAST_PIXELS that differ from the reference and from each other."""
    got, ref = images[Role.CANDIDATE], images[Role.REFERENCE]
    kinds = [k for k in ("color", *GEOMETRY_KINDS) if k in got and k in ref
             and as_bytes(got[k]).shape == as_bytes(ref[k]).shape]
    if not kinds:
        return None
    h, w = as_bytes(got[kinds[0]]).shape[:2]
    reads: list[tuple[str, Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]]] = [
        (f"read at index {form.text}", partial(output_read, form=form))
        for form in OUTPUT_FORMS[1:]]
    reads.append(("filtered as -filter does, each tap read at "
                  f"{TAP_FORMS[0].text} of a buffer of the image's own size (the -filter "
                  "path taken without -filter)",
                  partial(taps_read, form=TAP_FORMS[0], kernel=K, divisor=16.0, size=(w, h))))
    for what, read in reads:
        moved = np.zeros((h, w), bool)
        for k in kinds:
            predicted, defined = read(as_values(ref[k]).astype(np.float64))
            mine, theirs = as_bytes(got[k]), as_bytes(ref[k])
            if defined.mean() < READ_DEFINED or \
                    (differs(as_bytes(predicted), mine) & defined).sum() > \
                    thresholds.FAIL_SHARE * defined.sum() or \
                    (mine[defined] != np.median(mine[defined], axis=0)).any(axis=-1).sum() < \
                    CONTRAST_PIXELS:
                break
            moved |= differs(theirs, mine) & defined
        else:
            if moved.sum() >= CONTRAST_PIXELS:
                rendered = f" ({said})" if said else ""
                return Located((RENDER,), (
                    f"on the {defined.sum()} pixels ({defined.mean():.0%}) whose read stays "
                    f"inside the buffer, your {', '.join(kinds)} images{rendered} are the "
                    f"reference's values {what}"
                    + ("" if defined.all() else "; the others read outside it (undefined in "
                       "C)") + ": whole pixels moved, which the pixel loop or the writing of "
                    "the images does"), moved)
    return None


def everywhere(parts: Parts, changed: np.ndarray) -> bool:
    hit = parts.images["object"] >= 0
    return bool(hit.any() and (~hit).any() and changed[hit].mean() >= EVERYWHERE_SHARE
                and changed[~hit].mean() >= EVERYWHERE_SHARE)


def color_place(parts: Parts, changed: np.ndarray, said: str = "") -> Located:
    """A color difference whose geometry matches (said: how the images were rendered, where
    not as the case asks)."""
    hit = parts.images["object"] >= 0
    color = f"the color {said}" if said else "the color"
    if everywhere(parts, changed):
        return Located((RENDER,), f"{color} differs on {changed[hit].mean():.0%} of the "
                       f"objects' pixels and {changed[~hit].mean():.0%} of the background's "
                       "while the normals and depth match: a change every pixel gets "
                       "(traceRay returns the background before any shading)", changed)
    on_objects = int((changed & hit).sum())
    if on_objects == 0 and hit.sum() >= max(CONTRAST_PIXELS, CONTRAST_SHARE * hit.size):
        return Located((TRACE,), f"{color} differs only on the background "
                       f"({changed.sum()} pixels) while every object matches: the color of a "
                       "ray that hits nothing", changed)
    lights = sorted({f"{type(light).__name__}::getIllumination"
                     for light in parts.scene.lights})
    return Located(("Material::shade", *lights, TRACE),
                   f"{color} differs on {on_objects} pixels of objects while the normals and "
                   "depth match: the shading (the Phong terms, the light's direction, color "
                   "and falloff, the light loop and the ambient term)", changed)


def geometry_changed(kinds: list[KindVerdict], images: dict[Role, dict[str, np.ndarray]],
                     shape: tuple[int, ...]) -> tuple[list[str], np.ndarray] | None:
    """The failing geometry kinds that tell where the geometry differs, and the pixels where
    one of them does; None where an image is not of the case's size."""
    failing = {k.kind for k in kinds if k.verdict == Verdict.FAIL}
    # a geometry kind a change of the whole output explains (an inverted depth) is no
    # evidence of where the geometry differs
    geometry = [k for k in GEOMETRY_KINDS if k in failing and k in images[Role.CANDIDATE]
                and not findings.diagnose(k, False, images[Role.REFERENCE][k],
                                          images[Role.CANDIDATE][k])]
    changed = np.zeros(shape, bool)
    for k in geometry:
        ref, got = as_bytes(images[Role.REFERENCE][k]), as_bytes(images[Role.CANDIDATE][k])
        if ref.shape[:2] != changed.shape or got.shape != ref.shape:
            return None
        changed |= differs(ref, got)
    return geometry, changed


def localise(case: Case, verdict: KindVerdict,
             off: dict[str, tuple[np.ndarray | None, np.ndarray | None]],
             flags: list[str], one: OneRay | None,
             on: dict[str, tuple[np.ndarray | None, np.ndarray]] | None = None
             ) -> Finding | None:
    """The located finding of a failing kind, or None where no rule applies. off: the
    flag-off renders feature_findings made (flag -> reference's, candidate's); on: the
    reference's image of the kind with each flag the case does not ask for, and the
    candidate's of the case (runs_unasked)."""
    kind = verdict.kind
    parts = one.parts if one is not None else None
    scene = parts.scene if parts is not None else case_scene(case)
    if scene is None:
        return None
    pixels = case.request.width * case.request.height
    located = follows_flag(kind, flags, off, scene, pixels)
    if located is None and on:
        located = runs_unasked(kind, on, pixels)
    if located is not None:
        return located.finding()
    if one is None or parts is None:
        return None
    kinds, images = one.kinds, one.images
    unwritten_lines = blank_lines(images, one.said)
    if unwritten_lines is not None:
        return unwritten_lines.finding()
    moved = read_elsewhere(images, one.said)
    if moved is not None:
        return moved.finding()
    failing = {k.kind for k in kinds if k.verdict == Verdict.FAIL}
    read = geometry_changed(kinds, images, parts.images["object"].shape)
    if read is None:
        return None
    geometry, changed = read
    if geometry:
        named = " and ".join(geometry)
        if any(k not in case.request.kinds for k in geometry):
            named += " (rendered too: this case asks for its color alone)"
        if one.said:
            named += f" {one.said}"
        placed = whole_lines(changed, named, parts.images["object"]) or \
            geometry_place(parts, changed, named)
        if placed is None and everywhere(parts, changed):
            # an intersect that covers the whole image looks the same (measured on the
            # mutation benchmark's tuning sample: Renderer::Render in 24 of 35 kinds)
            placed = Located((RENDER, *intersects(parts.scene)),
                             f"the {named} differ on nearly every pixel, "
                             "background too: the primary rays, the way the images are "
                             "written, or an object that covers the whole image", changed)
        placed = placed or one_intersect(parts, changed, named)
        return None if placed is None else placed.finding()
    if kind != "color" or any(k not in images[Role.CANDIDATE] or k in failing
                              for k in GEOMETRY_KINDS):
        return None  # without matching geometry images, shading cannot be told from geometry
    ref, got = as_bytes(images[Role.REFERENCE]["color"]), as_bytes(images[Role.CANDIDATE]["color"])
    if ref.shape[:2] != parts.images["object"].shape or got.shape != ref.shape:
        return None
    return color_place(parts, differs(ref, got), one.said).finding()
