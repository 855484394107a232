"""Where to look when no known mistake reproduces an image (harness/diagnosis/localise.py), and
symptoms that lead only where their own model explains the image: renderers with a bug no
catalogue entry makes (tests/wrappers/), shares and counts by hand from the images."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
from test_findings import REPO, TRACER, Corrupted, checked, reference
from test_findings_geometry import object_image

from raycheck.harness.case_settings import CaseSettings
from raycheck.harness.catalog import scene_headers
from raycheck.harness.diagnosis.case import case_views, split_symptoms
from raycheck.harness.diagnosis.cross_case import cleared, object_views
from raycheck.harness.diagnosis.localise import (
    OneRay,
    blank_lines,
    geometry_changed,
    geometry_place,
    one_intersect,
    read_elsewhere,
    shows_nothing,
    whole_lines,
)
from raycheck.harness.judge import findings
from raycheck.harness.judge.findings import FlagPair
from raycheck.harness.judge.parts import Parts, reference_parts
from raycheck.harness.judge.verdict import KindVerdict, Tolerance, judge_deterministic
from raycheck.harness.pipeline.case import run_case
from raycheck.harness.pipeline.matrix import Matrix, Runner, matrix_jobs
from raycheck.harness.records import CaseRecord, ObjectView, Role, Verdict
from raycheck.tracer.pixel_index import OUTPUT_FORMS, TAP_FORMS, output_read, taps_read
from raycheck.tracer.render import FILTER_KERNEL
from raycheck.tracer.scene import load_scene
from raycheck.tracer.shade.auxiliary import SceneObjectInfo, scene_objects

SPHERES = REPO / "scenes" / "course" / "spheres_mirror.txt"  # five spheres and a plane
SHADOWS = REPO / "scenes" / "features" / "shadows.txt"  # a plane, two spheres, a cube mesh
ELLIPSOID = REPO / "scenes" / "course" / "ellipsoid.txt"  # one sphere, transformed; a plane
SIZE = 24


def differing(result, kinds: tuple[str, ...], size: int = SIZE) -> np.ndarray:
    """Pixels where a channel of any of the kinds differs by more than one level."""
    out = np.zeros((size, size), bool)
    for kind in kinds:
        a, b = reference(result, kind), reference(result, kind, "candidate")
        out |= np.abs(a - b).max(axis=2) > 1
    return out


def test_a_sphere_bug_is_located_in_sphere_intersect():
    """Every sphere intersected at 0.8 times its radius: the normals and depth differ on the
    spheres only (their silhouettes shrink inwards, on sphere pixels of the reference), while
    the plane and the cube mesh, in view, match: every kind's top finding names
    Sphere::intersect, with the count of differing pixels."""
    result = checked("sphere_shrunk", SHADOWS, "plain", size=SIZE)
    changed = differing(result, ("normals", "depth"))
    spheres = np.isin(object_image(SHADOWS, SIZE),
                      [o.index for o in scene_objects(load_scene(SHADOWS)) if o.kind == "sphere"])
    assert (changed & ~spheres).sum() == 0  # by construction: the spheres only shrink
    for kind in result.kinds:
        assert kind.verdict == "fail"
        top = kind.findings[0]
        assert top.code == "located"
        assert top.message == (
            "Sphere::intersect: no known mistake reproduces this image; the evidence points "
            f"here: the normals and depth differ only on the spheres (2 in the scene) and at "
            f"their silhouettes: 100% of the {changed.sum()} differing pixels on them, 100% "
            "within 2 pixels; the other objects match")


def test_against_planes_alone_a_sphere_bug_is_not_told_from_the_primary_rays():
    """spheres_mirror.txt: spheres on a floor plane, nothing else. A plane matches under a
    primary ray a little off too, so the finding names both places, neither as the one."""
    result = checked("sphere_shrunk", SPHERES, "plain", size=SIZE)
    top = result.kinds[0].findings[0]
    assert top.code == "located"
    assert top.message.startswith("no known mistake reproduces this image; look at "
                                  "Sphere::intersect or Renderer::Render: the normals and "
                                  "depth differ only on the spheres (5 in the scene)")
    assert top.message.endswith("(only planes, which a primary ray a little off leaves as "
                                "they are)")


def test_whole_rows_or_columns_are_the_pixel_loop():
    """The first column and the sixth row differ, whatever they show (the reference has an
    object in rows 3-7, columns 0-5, background elsewhere): Renderer::Render. Rows of
    background alone are no such evidence: a plane covering the sky changes whole rows."""
    objects = np.full((10, 10), -1)
    objects[3:8, :6] = 0
    changed = np.zeros((10, 10), bool)
    changed[:, 0] = changed[5, :] = True
    changed[4, 4] = True  # one more pixel: 19 of 20 (95%) in whole lines
    located = whole_lines(changed, "normals", objects)
    assert located is not None and located.functions == ("Renderer::Render",)
    assert located.evidence == ("the normals differ in 1 whole rows and 1 whole columns of the "
                                "image, whatever they show (95% of the 20 differing pixels): "
                                "the pixel loop")
    changed[3:6, 3:6] = True  # 25 pixels, 19 in lines: 76%
    assert whole_lines(changed, "normals", objects) is None
    sky = np.zeros((10, 10), bool)
    sky[:3, :] = True  # three rows of background only
    assert whole_lines(sky, "normals", objects) is None


def test_black_lines_in_every_image_normals_too_are_pixels_never_written():
    """4x4 images of one value each (color 50, normals 200, depth 30): the candidate's black on
    the top three rows in all three, the bottom row as the reference's: Renderer::Render. So
    too the color written in the first column alone, the normals and depth nowhere (a loop
    left after a pixel's first image). The same with the normals written there (black color
    and depth alone are also a dark scene's misses), or with a written pixel differing too,
    is no such evidence."""
    ref = {k: np.full((4, 4, 3), v, np.uint8) for k, v in
           (("color", 50), ("normals", 200), ("depth", 30))}
    got = {k: v.copy() for k, v in ref.items()}
    for image in got.values():
        image[:3] = 0
    located = blank_lines({Role.REFERENCE: ref, Role.CANDIDATE: got})
    assert located is not None and located.functions == ("Renderer::Render",)
    assert located.evidence == (
        "your color, normals, depth images differ only where they are black on whole rows or "
        "columns, the normals on 3 whole rows, which no written pixel is (a unit normal's "
        "(n + 1)/2 has a channel above 0, a miss's is 0.5): pixels never written, by the pixel "
        "loop (its bounds, a loop left early) or the loop that copies its values into the "
        "images")
    assert located.mask is not None and located.mask.sum() == 12
    column = {k: np.zeros_like(v) for k, v in ref.items()}
    column["color"][:, 0] = 50
    found = blank_lines({Role.REFERENCE: ref, Role.CANDIDATE: column}, "rendered so")
    assert found is not None and found.evidence.startswith(
        "your color, normals, depth images (rendered so) differ only where they are black on "
        "whole rows or columns, the normals on every pixel,")
    got["normals"][:3] = 200
    assert blank_lines({Role.REFERENCE: ref, Role.CANDIDATE: got}) is None
    got["normals"][:3] = 0
    got["color"][3, 0] = 60  # one more pixel differs: 1 of 16, over the tolerance's share
    assert blank_lines({Role.REFERENCE: ref, Role.CANDIDATE: got}) is None


def test_pixels_read_from_elsewhere_in_the_buffer_are_the_pixel_loops():
    """12x12 images of random values, the candidate's each pixel read at index y * w - x (the
    bottom row's x > 0 read before the buffer: left at 0.3, as garbage), or filtered as -filter
    does from the 12x12 buffer itself (the -filter path without -filter: what reads past the
    buffer at 0.3): Renderer::Render, with the pixels whose read is defined. Random noise of
    the reference, or a candidate of one value, is no such evidence."""
    rng = np.random.default_rng(3)
    ref = {k: rng.random((12, 12, 3)).astype(np.float32) for k in ("color", "normals", "depth")}

    def read(reader) -> dict[str, np.ndarray]:
        out = {}
        for k, v in ref.items():
            image, defined = reader(v.astype(np.float64))
            out[k] = np.where(defined[..., None], image, 0.3).astype(np.float32)
        return out

    minus = next(f for f in OUTPUT_FORMS if f.text == "y * w - x")
    located = read_elsewhere({Role.REFERENCE: ref,
                              Role.CANDIDATE: read(lambda v: output_read(v, minus))})
    assert located is not None and located.functions == ("Renderer::Render",)
    assert located.evidence == (
        "on the 133 pixels (92%) whose read stays inside the buffer, your color, normals, depth "
        "images are the reference's values read at index y * w - x; the others read outside "
        "it (undefined in C): whole pixels moved, which the pixel loop or the writing of the "
        "images does")
    _, defined = taps_read(ref["color"], TAP_FORMS[0], FILTER_KERNEL, 16.0, (12, 12))
    located = read_elsewhere({Role.REFERENCE: ref, Role.CANDIDATE: read(
        lambda v: taps_read(v, TAP_FORMS[0], FILTER_KERNEL, 16.0, (12, 12)))}, "rendered so")
    assert located is not None and located.evidence.startswith(
        f"on the {defined.sum()} pixels ({defined.mean():.0%}) whose read stays inside the "
        "buffer, your color, normals, depth images (rendered so) are the reference's values "
        "filtered as -filter does, each tap read at (3 * y + j) * w + 3 * x + i of a buffer of "
        "the image's own size (the -filter path taken without -filter)")
    noisy = {k: np.clip(v + rng.normal(0, 0.05, v.shape), 0, 1).astype(np.float32)
             for k, v in ref.items()}
    assert read_elsewhere({Role.REFERENCE: ref, Role.CANDIDATE: noisy}) is None
    gray = {k: np.full_like(v, 0.5) for k, v in ref.items()}
    assert read_elsewhere({Role.REFERENCE: ref, Role.CANDIDATE: gray}) is None


def test_a_program_that_writes_its_first_row_alone_is_located_in_render():
    """Every image black but its bottom row (row y = 0, the pixel loop's first): the color's
    and the normals' top finding names Renderer::Render, with the 23 black rows of the 24.
    The depth image alone (a miss's depth is black too) is what rays that leave the image
    above its first row give: the cause search's camera mistake, Renderer::Render's too."""
    result = checked("first_row", SHADOWS, "plain", size=SIZE)
    assert [k.kind for k in result.kinds] == ["color", "normals", "depth"]
    for kind in result.kinds:
        assert kind.verdict == "fail"
        top = kind.findings[0]
        assert top.message.startswith("Renderer::Render: ")
        if kind.kind != "depth":
            assert top.code == "located"
            assert top.message.startswith(
                "Renderer::Render: no known mistake reproduces this image; the evidence points "
                "here: your color, normals, depth images differ only where they are black on "
                "whole rows or columns, the normals on 23 whole rows,")


def test_a_transformed_sphere_alone_is_not_told_from_transform():
    """ellipsoid.txt's only sphere is under a transform and no other object is: its bug may be
    Sphere::intersect's or Transform::intersect's (and, against a plane alone, the primary
    rays'), and the finding says each (no function is named as the one)."""
    result = checked("sphere_shrunk", ELLIPSOID, "plain", size=SIZE)
    top = result.kinds[0].findings[0]
    assert top.code == "located"
    assert top.message.startswith("no known mistake reproduces this image; look at "
                                  "Sphere::intersect, Renderer::Render or Transform::intersect: "
                                  "the normals and depth differ only on the spheres (1 in the "
                                  "scene)")
    assert top.message.endswith("; every one of them is transformed")


def test_a_case_that_asks_for_color_alone_gets_its_geometry_rendered_to_locate_a_bug():
    """shadows.txt with -shadows: the case asks for the color alone, and a sphere bug changes
    it much as a shading one would. The normals and depth, rendered with the case's flags (the
    same primary rays), differ on the spheres only: Sphere::intersect, as in the plain case."""
    result = checked("sphere_shrunk", SHADOWS, "shadows", size=SIZE)
    assert [k.kind for k in result.kinds] == ["color"]
    assert result.kinds[0].findings[0].message.startswith(
        "Sphere::intersect: no known mistake reproduces this image; the evidence points here: "
        "the normals and depth (rendered too: this case asks for its color alone) differ only "
        "on the spheres (2 in the scene)")


def test_a_filter_or_jitter_case_is_located_on_its_render_at_three_times_the_size():
    """shadows.txt with -filter, and with -jitter: the sphere bug changes the filtered (or
    jittered) image, which the one-ray-a-pixel rules cannot read; rendered without the flag at
    three times the size, the normals and depth differ on the spheres alone, as they do in the
    plain case at that size (its differing pixels counted here)."""
    plain = checked("sphere_shrunk", SHADOWS, "plain", size=3 * SIZE)
    changed = differing(plain, ("normals", "depth"), 3 * SIZE).sum()
    for feature, flag in (("filter", "-filter"), ("jitter", "-jitter")):
        result = checked("sphere_shrunk", SHADOWS, feature, size=SIZE)
        for kind in result.kinds:
            assert kind.verdict == "fail"
            assert kind.findings[0].message == (
                "Sphere::intersect: no known mistake reproduces this image; the evidence points "
                f"here: the normals and depth rendered without {flag} at three times the size "
                f"differ only on the spheres (2 in the scene) and at their silhouettes: 100% of "
                f"the {changed} differing pixels on them, 100% within 2 pixels; the other "
                "objects match")


def planes_and_a_sphere(sphere_pixels: int) -> Parts:
    """A 10x10 object image of a plane (0) with a sphere (1) of `sphere_pixels` in a corner, or
    none in view; the scene holds both."""
    obj = np.zeros((10, 10), np.int32)
    obj.flat[:sphere_pixels] = 1
    objects = [SceneObjectInfo(0, "plane", 0, 1, False, None, 0, 1),
               SceneObjectInfo(1, "sphere", 0, 2, False, None, 1, 1)]
    return Parts({"object": obj}, np.zeros((10, 10, 3), np.float32), objects,
                 load_scene(SPHERES))  # the scene is not read


def test_a_difference_on_the_only_kind_in_view_names_nothing_where_the_scene_holds_more():
    """Half the plane's pixels differ and the sphere is out of view (or too small to match):
    the sphere may have grown over the plane, so neither Plane::intersect nor a list that
    leaves Sphere::intersect out is a finding. With the sphere gone from the scene, the plane
    alone is left, beside the primary rays."""
    changed = np.zeros((10, 10), bool)
    changed[5:, :] = True
    assert geometry_place(planes_and_a_sphere(0), changed, "normals") is None
    assert geometry_place(planes_and_a_sphere(3), changed, "normals") is None
    alone = planes_and_a_sphere(0)
    alone = Parts(alone.images, alone.color, alone.objects[:1], alone.scene)
    found = geometry_place(alone, changed, "normals")
    assert found is not None and found.functions == ("Plane::intersect", "Renderer::Render")
    assert found.evidence == ("the normals differ only on the planes (1 in the scene), the only "
                              "objects in the scene: 100% of the 50 differing pixels on them, "
                              "100% within 2 pixels")


def a_sphere(transformed: bool) -> Parts:
    """A 10x10 object image of one sphere (0) on its first 9 pixels (row 0, columns 0-8),
    background elsewhere; the scene holds it alone."""
    obj = np.full((10, 10), -1, np.int32)
    obj.flat[:9] = 0
    return Parts({"object": obj}, np.zeros((10, 10, 3), np.float32),
                 [SceneObjectInfo(0, "sphere", 0, 1, transformed, None, 0, 1)],
                 load_scene(SPHERES))  # the scene is not read


def test_a_difference_off_the_objects_of_a_scene_of_one_intersect_leaves_it_and_the_rays():
    """The scene holds a sphere alone, and 20 pixels differ: its 9 and 11 of the background
    (an object that grew differs off the objects, so no confinement is asked): its intersect
    or the primary rays, and the Transform where it is transformed."""
    changed = np.zeros((10, 10), bool)
    changed.flat[:20] = True
    found = one_intersect(a_sphere(False), changed, "normals")
    assert found is not None and found.functions == ("Sphere::intersect", "Renderer::Render")
    assert found.evidence == ("the normals differ on 20 pixels, 11 of them where the reference "
                              "shows the background; the scene holds spheres alone (1)")
    moved = one_intersect(a_sphere(True), changed, "normals")
    assert moved is not None and moved.functions == ("Sphere::intersect", "Renderer::Render",
                                                     "Transform::intersect")
    assert moved.evidence.endswith("the scene holds spheres alone (1, some transformed)")
    assert one_intersect(planes_and_a_sphere(9), changed, "normals") is None  # two intersects


def test_an_objects_view_counts_its_silhouette():
    """The sphere's own 9 pixels match, and row 2 (10 pixels, within 2 pixels of it) differs:
    of its 30 pixels with their silhouette (rows 0-2), a third differ, so it does not match as
    a witness for the other cases (it may have grown); row 5, further away, leaves it matching.
    Rendered at three times the size, its pixels count in the case's (27 sub-pixels: 3)."""
    near = np.zeros((10, 10), bool)
    near[2, :] = True
    (view,) = object_views(a_sphere(False), near)
    assert (view.kind, view.transformed, view.pixels) == ("sphere", False, 9)
    assert view.changed == 10 / 30
    far = np.zeros((10, 10), bool)
    far[5, :] = True
    assert object_views(a_sphere(False), far)[0].changed == 0.0
    obj = np.full((30, 30), -1, np.int32)
    obj[:3, :9] = 0
    big = Parts({"object": obj}, np.zeros((30, 30, 3), np.float32), a_sphere(False).objects,
                load_scene(SPHERES))
    (view3,) = object_views(big, np.zeros((30, 30), bool), 3)
    assert (view3.pixels, view3.scale) == (3, 3)


def test_a_view_at_three_times_the_size_does_not_clear_the_primary_rays():
    """Matching spheres clear Renderer::Render in the case's own image, not in a -jitter or
    -filter case's render at three times the size (other rays: a constant of their formula
    moves them less there); their intersect and the Transform they clear either way."""
    own = ObjectView("sphere", True, 100, 0.0)
    assert set(cleared(own, {"sphere"})) == {"Sphere::intersect", "Transform::intersect",
                                             "Renderer::Render"}
    assert set(cleared(replace(own, scale=3), {"sphere"})) == {"Sphere::intersect",
                                                               "Transform::intersect"}


def test_a_case_a_whole_image_change_explains_gives_no_views():
    """A program that writes every image transposed: a change of the whole image explains its
    normals and depth, which then say nothing of which objects differ (no pixel counts as
    changed there); the case gives no views, which would read as every object matching and
    clear every function for the program's other cases."""
    matrix = Matrix(scene_headers([SHADOWS]), Corrupted("transpose"), TRACER, CaseSettings(),
                    size=(SIZE, SIZE), features=frozenset({"plain"}))
    (case,), _ = matrix.cases()
    result = run_case(case, matrix.candidate, matrix.reference, matrix.settings)
    images = {role: {k: np.asarray(v) for k, v in result.images[role].items()}
              for role in (Role.REFERENCE, Role.CANDIDATE)}
    kinds = [judge_deterministic(k, images[Role.REFERENCE][k], images[Role.CANDIDATE][k],
                                 Tolerance()) for k in ("color", "normals", "depth")]
    assert all(k.verdict == Verdict.FAIL for k in kinds)
    parts = reference_parts(case)
    assert parts is not None
    read = geometry_changed(kinds, images, parts.images["object"].shape)
    assert read is not None and read[0] == [] and not read[1].any()  # nothing "changed"
    assert case_views(OneRay(kinds, images, parts)) == ((), ())


def program_tops(defect: str, *scenes, features: frozenset[str] = frozenset({"plain"})
                 ) -> dict[str, str]:
    """case id (the scene's, for plain cases) -> the top finding's message, the defect's
    renderer checked on the scenes together (one program: its cases contrast each other)."""
    matrix = Matrix(scene_headers(list(scenes)), Corrupted(defect), TRACER, CaseSettings(),
                    size=(SIZE, SIZE), features=features)
    rows: list[CaseRecord] = [o.row for o in Runner(quiet=True).run(matrix_jobs(matrix)[0])]
    tops = {row.scene if row.feature == "plain" else f"{row.scene}/{row.feature}":
            row.top_finding() or row.error for row in rows}
    return {case: top.message for case, top in tops.items() if top is not None}


def test_other_cases_of_the_program_narrow_a_located_finding_to_one_function():
    """sphere_shrunk on three scenes at once. In shadows.txt the plane and the cube mesh match
    beside the spheres, so Sphere::intersect is named there; spheres_mirror.txt (spheres on a
    plane) alone leaves the primary rays, ellipsoid.txt (one transformed sphere) the primary
    rays and Transform::intersect too. shadows.txt's cube mesh, curved and transformed, matches:
    the primary rays and the Transform are right, and both name Sphere::intersect, saying
    which case showed it."""
    tops = program_tops("sphere_shrunk", SPHERES, SHADOWS, ELLIPSOID)
    assert tops["features/shadows"].startswith("Sphere::intersect: no known mistake")
    assert tops["course/spheres_mirror"].startswith(
        "Sphere::intersect: no known mistake reproduces this image; the evidence points here: "
        "the normals and depth differ only on the spheres (5 in the scene)")
    assert tops["course/spheres_mirror"].endswith(
        "; across the program's cases, not Renderer::Render: in features/shadows/plain its "
        "meshes match, which primary rays a little off would change")
    assert tops["course/ellipsoid"].startswith("Sphere::intersect: no known mistake")
    assert tops["course/ellipsoid"].endswith(
        "; across the program's cases, not Renderer::Render: in features/shadows/plain its "
        "meshes match, which primary rays a little off would change; not "
        "Transform::intersect: in features/shadows/plain its transformed meshes match")


def test_a_jittered_case_is_narrowed_by_the_programs_other_cases():
    """ellipsoid.txt with -jitter: its render at three times the size leaves Sphere::intersect,
    the primary rays and the Transform (its one sphere is transformed); shadows.txt's plain
    case, its cube mesh matching, clears both others, after the jittered case has run."""
    tops = program_tops("sphere_shrunk", SHADOWS, ELLIPSOID,
                        features=frozenset({"plain", "jitter"}))
    assert tops["course/ellipsoid/jitter"].startswith(
        "Sphere::intersect: no known mistake reproduces this image; the evidence points here: "
        "the normals and depth rendered without -jitter at three times the size differ only "
        "on the spheres (1 in the scene)")
    assert tops["course/ellipsoid/jitter"].endswith(
        "; across the program's cases, not Renderer::Render: in features/shadows/plain its "
        "meshes match, which primary rays a little off would change; not "
        "Transform::intersect: in features/shadows/plain its transformed meshes match")


def test_without_other_objects_that_match_nothing_is_narrowed():
    """spheres_mirror.txt and ellipsoid.txt together: every sphere differs, and the only other
    objects are planes, which do not show the primary rays right (a plane matches under a ray a
    little off) and are not transformed: both findings still leave several functions."""
    tops = program_tops("sphere_shrunk", SPHERES, ELLIPSOID)
    assert tops["course/spheres_mirror"].startswith(
        "no known mistake reproduces this image; look at Sphere::intersect or Renderer::Render")
    assert tops["course/ellipsoid"].startswith(
        "no known mistake reproduces this image; look at Sphere::intersect, Renderer::Render "
        "or Transform::intersect")


def test_a_flag_the_program_runs_unasked_is_the_gate_in_trace_ray():
    """A program that tests shadows without -shadows: its plain color image is the
    reference's with the flag, so the flag's gate in Renderer::traceRay runs where the case
    does not ask for it. One that follows 4 mirror bounces without -bounces is a known
    mistake's: 4 bounces more than asked."""
    result = checked("always_shadows", SPHERES, "plain", size=SIZE)
    color = next(k for k in result.kinds if k.kind == "color")
    assert color.verdict == "fail"
    assert color.findings[0].message == (
        "Renderer::traceRay: no known mistake reproduces this image; the evidence points "
        "here: your color image matches the reference's rendered with -shadows, which this "
        "case does not ask for: the shadow test runs without it")
    result = checked("always_bounces", SPHERES, "plain", size=SIZE)
    color = next(k for k in result.kinds if k.kind == "color")
    assert color.verdict == "fail" and color.findings[0].code == "cause:reflection_depth"
    assert color.findings[0].message.startswith(
        "Renderer::traceRay: your program follows 4 mirror bounce(s) more than -bounces asks "
        "for (negative: fewer). With this mistake, the reference reproduces your images: "
        "100.0% of pixels match")


def test_images_of_the_background_alone_list_what_makes_every_ray_miss():
    """The reference shows a sphere on 9 pixels of a background of 10; a candidate whose color
    image is 10 everywhere (and its normals one value) shows nothing but the background: the
    camera, traceRay's hit and each intersect of the scene are listed. One pixel of another
    value, or a background of another color, and it shows something."""
    parts = a_sphere(False)
    ref = np.full((10, 10, 3), 10, np.uint8)
    ref.reshape(-1, 3)[:9] = 200
    sky = np.full((10, 10, 3), 10, np.uint8)
    miss = np.full((10, 10, 3), 128, np.uint8)
    images = {Role.REFERENCE: {"color": ref}, Role.CANDIDATE: {"color": sky, "normals": miss}}
    found = shows_nothing(images, parts)
    assert found is not None and found.functions == (
        "Renderer::Render", "Renderer::traceRay", "Plane::intersect", "Sphere::intersect")
    assert found.evidence == (
        "your images show nothing but the background, where the reference's show objects on 9 "
        "pixels: every primary ray misses, as it does where the camera looks away, where "
        "traceRay does not find the hit and where every intersect misses")
    speck = sky.copy()
    speck[5, 5] = 11
    other = np.full((10, 10, 3), 12, np.uint8)
    shaded = miss.copy()
    shaded[0, 0] = 200
    for candidate in ({"color": speck}, {"color": other}, {"color": sky, "normals": shaded}):
        assert shows_nothing({**images, Role.CANDIDATE: candidate}, parts) is None


def test_a_camera_that_looks_away_is_not_named_where_every_ray_misses():
    """The tracer with ndc y's final 1 as -4: its rays look above every object of
    spheres_mirror. A camera mistake reproduces the images (ndc y's shift as -1 does too), but
    so would a traceRay that never finds the hit: the lead lists them, the cause follows."""
    result = checked("none@ndc_y_shift.constant=-4", SPHERES, "plain", size=SIZE)
    for kind in result.kinds:
        assert kind.verdict == "fail"
        top, cause = kind.findings[:2]
        assert top.code == "located" and top.functions == (
            "Renderer::Render", "Renderer::traceRay", "Plane::intersect", "Sphere::intersect")
        assert top.message.startswith("the mistakes that make every ray miss reproduce these "
                                      "images alike; look at Renderer::Render, ")
        assert cause.code.startswith("cause:ndc_y_")


def test_the_tracer_gets_no_located_finding():
    result = checked("none", SPHERES, "plain", size=SIZE)
    assert all(k.verdict == "pass" and not k.findings for k in result.kinds)


# --- symptoms: they lead only where they explain the image ----------------------------------
def flat(value: int) -> np.ndarray:
    return np.full((10, 10, 3), value, np.int32)


def test_a_symptom_that_explains_the_image_leads_with_its_question():
    """The reference lights the left half (200) and shadows the right (50; without shadows 200
    everywhere); the candidate shadows 10 pixels of the lit half (100) and nothing else
    differs: 10 of the 50 lit pixels (20.0%), nothing outside them: it explains the image and
    asks its question."""
    ref_on, got_on = flat(200), flat(200)
    ref_on[:, 5:] = got_on[:, 5:] = 50  # the shadowed right half, in both
    got_on[0, :5] = got_on[1, :5] = 100  # the acne: 10 lit pixels shadowed
    acne = findings.shadow_acne(FlagPair(ref_on, flat(200)), FlagPair(got_on, flat(200)))
    assert acne is not None and acne.unexplained == 0.0 and acne.explains
    assert acne.record().message == (
        "your image shadows 20.0% of the pixels the reference lights (10 pixels): does the "
        "shadow ray start off the surface (p + epsilon*dir)?")


def test_a_shading_symptom_does_not_lead_where_the_primary_hits_differ():
    """The acne above explains the color image, but the case's normals (rendered for it) differ
    too: a shadow ray's start cannot move a primary hit, so the acne is a hint and localisation
    leads. Where only the color differs, it leads as before; without one-ray images too."""
    ref_on, got_on = flat(200), flat(200)
    ref_on[:, 5:] = got_on[:, 5:] = 50
    got_on[0, :5] = got_on[1, :5] = 100
    acne = findings.shadow_acne(FlagPair(ref_on, flat(200)), FlagPair(got_on, flat(200)))
    assert acne is not None and acne.explains

    def one(normals: Verdict) -> OneRay:
        return OneRay([KindVerdict("color", Verdict.FAIL), KindVerdict("normals", normals)],
                      {}, None)

    leads, hints = split_symptoms([acne], one(Verdict.FAIL))
    assert leads == [] and [h.record().message for h in hints] == [
        "your image shadows 20.0% of the pixels the reference lights (10 pixels)"]
    for matched in (one(Verdict.PASS), None):
        leads, hints = split_symptoms([acne], matched)
        assert [f.record().message for f in leads] == [acne.record().message] and hints == []


def test_a_symptom_that_goes_with_filter_follows_the_filter_code():
    """The color of a -filter case 12 levels brighter everywhere, and only with -filter: a
    constant offset explains the image, but rendered without -filter at three times the size
    the images match. The -filter code is Renderer::Render's: it leads, the offset after it
    (its guess, an ambient term counted twice, would show without -filter too)."""
    result = checked("filter_offset", SHADOWS, "filter", size=SIZE)
    color = next(k for k in result.kinds if k.kind == "color")
    assert color.verdict == "fail"
    assert color.findings[0].message.startswith(
        "Renderer::Render: no known mistake reproduces this image; the evidence points here: "
        "your color image differs only with -filter: rendered without it at three times the "
        "size (one ray at each sub-pixel position), its color image matches the reference's")
    assert color.findings[1].code == "constant_offset"


def test_a_symptom_that_leaves_most_of_the_image_is_a_hint_without_its_question():
    """The same acne, and 30 more pixels that differ in the shadowed half (another bug): 30 of
    the 100 pixels differ outside what acne accounts for, over the verdict's 0.5%: the finding
    is a hint, its observation alone."""
    ref_on, got_on = flat(200), flat(200)
    ref_on[:, 5:] = got_on[:, 5:] = 50
    got_on[0, :5] = got_on[1, :5] = 100
    got_on[4:10, 5:] = 90  # 30 shadowed pixels brighter
    acne = findings.shadow_acne(FlagPair(ref_on, flat(200)), FlagPair(got_on, flat(200)))
    assert acne is not None and acne.unexplained == 0.3 and not acne.explains
    assert acne.hint().record().message == (
        "your image shadows 20.0% of the pixels the reference lights (10 pixels)")
