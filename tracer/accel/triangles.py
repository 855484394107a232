"""The scene's triangles, intersected together in the render kernel (spec §5).

One BVH over all triangles. In course mode a transformed triangle keeps its object space: the
BVH holds it at its world-space place, and its test moves the ray into its instance's space
through the course's inverses, as the course does; where every triangle is in one instance,
the BVH holds them at their object-space places and the ray is moved once, before the search.
The course intersects each TriangleMesh through an octree, which for a ray with a direction
component of exactly zero (in the mesh's space) visits only some of the leaves the ray crosses
(tracer.accel.octree): for such rays the BVH leaves that mesh's triangles to the course's octree
traversal (tracer.accel.octree_traversal). Every other ray gets the brute-force answer, which the
octree gives too. Camera rays and directional lights' shadow rays, which share an origin or a
direction, may test lists of candidates instead of searching the BVH (screen_tiles.py,
shadow_grid.py): the same triangle test on every triangle they could be accepted by.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..kernel.backend import aligned_zeros, from_numpy, import_drjit
from ..kernel.vecmath import Types, dot, gather_packet, mat3_mul, normalize
from ..mistakes import hooks
from ..operators import Operator, Site, site_codes
from .bvh import BVH, build_bvh
from .flat_scene import NO_INSTANCE, ObjectTransform, TriangleSoup
from .octree import build_octree
from .octree_traversal import OctreeTraversal
from .shadow_grid import MAX_TRIANGLES as MAX_GRID_TRIANGLES
from .shadow_grid import DeviceGrid, shadow_grid
from .transform_sites import TransformSites
from .triangle_records import course_records
from .triangle_search import NO_TRIANGLE, TriangleSearch
from .wide_bvh import (
    INTEGER_SLOTS,
    wide_records,
)
from .wide_traversal import WideNodes, traverse

FLT_MAX = float(np.finfo(np.float32).max)
TRIANGLE_W_TOLERANCE = 1e-3
# Up to this many mesh spaces (world and transformed meshes' instances), a ray's direction is
# checked in each one before the octree loop, and the BVH reads the result from a lane bit
# mask; beyond it every ray enters the loop and the BVH checks every mesh triangle (slower).
MAX_MESH_SPACES = 32
# the sites of the triangle test and the interpolated normal (operators.py), vertex 0 first
WEIGHTS = (Site.TRIANGLE_WEIGHT_0, Site.TRIANGLE_WEIGHT_1, Site.TRIANGLE_WEIGHT_2)
VERTICES = (Site.TRIANGLE_VERTEX_0, Site.TRIANGLE_VERTEX_1, Site.TRIANGLE_VERTEX_2)
TERMS = (Site.TRIANGLE_TERM_0, Site.TRIANGLE_TERM_1, Site.TRIANGLE_TERM_2)
# the sites that change which rays hit a triangle, and where: a BVH bounds the course's
# triangles only, so that renders with one of them on test every triangle, a mesh's those of
# the octree leaves its ray visits (MistakenTriangles)
RESHAPING = (Site.TRIANGLE_BEHIND, Site.TRIANGLE_ORIGIN, Site.TRIANGLE_U_INDEX,
             Site.TRIANGLE_V_INDEX, Site.TRIANGLE_U_LOW, Site.TRIANGLE_V_LOW,
             Site.TRIANGLE_UV_SUM, Site.TRIANGLE_INSIDE)
HOOKS = hooks(__name__, *site_codes(
    *RESHAPING, Site.TRIANGLE_ACCEPT, Site.TRIANGLE_WEIGHT0_ONE, Site.TRIANGLE_WEIGHT0_U,
    Site.TRIANGLE_WEIGHT0_V, *WEIGHTS, *VERTICES, *TERMS, Site.TRIANGLE_SUM_1,
    Site.TRIANGLE_SUM_2))


class TriangleSet(TransformSites):
    """Triangles on the device: records, BVH, instances and octrees, and their queries, with
    the course's triangle test (robust.py's subclass has its own)."""

    # shadow rays of a directional light may be answered by a grid of the course's records
    # (shadow_grid.py), whose test is the course's
    SHADOW_GRIDS = True
    unit = staticmethod(normalize)  # of interpolated shading normals
    world_unit = staticmethod(normalize)  # of normals transformed to world space

    def __init__(self, tris: TriangleSoup, types: Types, accel: str = "bvh",
                 octrees: bool = False, build=build_bvh,
                 instances: Sequence[ObjectTransform] = ()) -> None:
        """accel: "bvh", or "brute" (every ray tests every triangle, for checking the BVH);
        octrees: the course's mesh octrees for the rays they traverse degenerately; build:
        the BVH builder; instances: the transforms of tris.instance (course mode)."""
        self.T = types
        self.dr = import_drjit()
        self.count = len(tris)
        self.bvh: BVH | None = None
        self.octrees = octrees and bool(tris.meshes)
        self.instances = list(instances)
        self.levels = max((len(x.inverses) for x in self.instances), default=0)
        # every triangle in an untransformed mesh: rays the octree takes skip the BVH
        self.only_meshes = (self.octrees and not self.instances
                            and sum(n for _, n in tris.meshes) == self.count)
        # Triangles all in one instance (one transformed mesh) are searched in its space: the
        # ray enters it once, before the traversal, instead of at each triangle test, and
        # the BVH bounds the object-space triangles, tighter around a rotated mesh than
        # world-space boxes. The triangle test sees the same ray either way.
        self.one_instance = NO_INSTANCE
        self.one_inverses: list = []  # its matrices as run-time scalars (_upload_instances)
        self.one_normals: list = []
        self._grids: dict[tuple[float, ...], DeviceGrid | None] = {}  # shadow_grid's
        if self.instances and self.count and (tris.instance == tris.instance[0]).all():
            self.one_instance = int(tris.instance[0])
        if self.count:
            self._upload(tris, accel, build)

    def _upload(self, tris: TriangleSoup, accel: str, build) -> None:
        T, dr = self.T, self.dr
        permutation = np.arange(len(tris))
        if accel == "bvh":
            world = tris.bounds is not None and self.one_instance == NO_INSTANCE
            self.bvh = build(tris.bounds if world else tris.vertices)
            permutation = self.bvh.order
            rec, root_ref = wide_records(self.bvh)
            self.nodes = WideNodes(T, self._as_records(rec, INTEGER_SLOTS), root_ref,
                                   self.bvh.lo[0].tolist(), self.bvh.hi[0].tolist())
        v = tris.vertices[permutation].astype(np.float32)
        record = course_records(v)
        # in device order, what shadow grids are made of (the largest meshes get none)
        self._course_records = (record if self.SHADOW_GRIDS and len(v) <= MAX_GRID_TRIANGLES
                                else None)
        instance = tris.instance if self.instances else np.full(len(tris), NO_INSTANCE)
        # the spaces (instances) holding a mesh: a mesh triangle's space is 1 + its space's
        # position in this list (its bit in the lane masks of _degenerate), others hold 0
        self.mesh_instances = sorted({int(instance[s]) for s, _ in tris.meshes})
        space = np.zeros(len(tris), np.uint32)
        for s0, count in tris.meshes:
            space[s0:s0 + count] = 1 + self.mesh_instances.index(int(instance[s0]))
        self.tspace = from_numpy(T.UInt32, space[permutation]) if self.octrees else None
        self.trecord, normals = self._triangle_records(tris, permutation, record,
                                                       tris.normals[permutation])
        self.tnormals = T.Float(np.ascontiguousarray(normals.reshape(-1, 3),
                                                     dtype=T.np_float).ravel())
        self.tmaterial = from_numpy(T.UInt32, tris.material[permutation])  # one a triangle
        self.torder = from_numpy(T.UInt32, tris.order[permutation])
        self.tcount = dr.opaque(T.UInt32, self.count)
        if self.instances:
            self._upload_instances(instance[permutation])
        if self.octrees:
            inverse = np.empty(len(permutation), np.int64)
            inverse[permutation] = np.arange(len(permutation))
            self.octree = OctreeTraversal(
                [(build_octree(tris.vertices[s:s + n]), inverse[s:s + n], int(instance[s]))
                 for s, n in tris.meshes], T)

    def _upload_instances(self, instance: np.ndarray) -> None:
        """Per instance and level (innermost levels of short chains unused): M^-1 as 16
        floats, N = ((M3)^-1)^T as 3 rows (and each other matrix of normal_options), and the
        number of levels."""
        T, levels = self.T, self.levels
        inv = aligned_zeros((len(self.instances) * levels, 16), np.float32)
        options = len(self.normal_options(np.eye(4, dtype=np.float32),
                                          np.eye(3, dtype=np.float32)))
        nrm = np.zeros((options, len(self.instances) * levels, 3, 3), np.float32)
        for i, xf in enumerate(self.instances):
            for k, (m, n) in enumerate(zip(xf.inverses, xf.normal_matrices)):
                inv[i * levels + k] = m.ravel()
                nrm[:, i * levels + k] = self.normal_options(m, n)
        self.inst_inverse = T.Float(inv.ravel())
        # per normal option (normal_options), the levels' matrices
        self.inst_normals = [T.Float(option.ravel()) for option in nrm]
        self.inst_levels = from_numpy(T.UInt32, np.array([len(x.inverses)
                                                          for x in self.instances], np.uint32))
        self.tinstance = from_numpy(T.UInt32, instance.astype(np.uint32))
        if self.one_instance != NO_INSTANCE:
            # its matrices as run-time scalars (kernel parameters, broadcast once per packet)
            # rather than gathered at every traversal and hit: the same IEEE operations
            xf = self.instances[self.one_instance]
            self.one_inverses = [self._opaque_matrix(m) for m in xf.inverses]
            self.one_normals = [[self._opaque_matrix(option) for option in
                                 self.normal_options(m, n)]
                                for m, n in zip(xf.inverses, xf.normal_matrices)]

    def shadow_grid(self, direction: Sequence[float]) -> DeviceGrid | None:
        """The grid of the triangles for shadow rays along `direction` (world space; the float32
        values the kernel uses), made once per direction; None where the BVH answers them:
        robust mode and float64 (their tests differ), no BVH, a mesh too large for a grid, or
        transformed triangles in more than one instance (each test moves the ray into its
        own)."""
        key = tuple(float(np.float32(c)) for c in direction)
        if key not in self._grids:
            self._grids[key] = None
            course = (self.T.precision == "single" and self.bvh is not None
                      and self._course_records is not None)
            if course and (not self.instances or self.one_instance != NO_INSTANCE):
                d, condition = np.array(key, np.float64), 1.0
                if self.instances:  # into the one instance, as _in_one_instance moves rays
                    for m in self.instances[self.one_instance].inverses:
                        m3 = m[:3, :3].astype(np.float64)
                        d, condition = m3 @ d, condition * np.linalg.cond(m3)
                assert self._course_records is not None  # `course` holds: checked there
                grid = shadow_grid(self._course_records, d, float(condition))
                self._grids[key] = None if grid is None else DeviceGrid(grid, self.T)
        return self._grids[key]

    def _triangle_records(self, tris: TriangleSoup, permutation: np.ndarray,
                          record: np.ndarray, normals: np.ndarray):
        """The device records the triangle test reads (`record`: course_records, in device
        order) and the vertex normals (device order) shading interpolates."""
        return self._as_records(record, ()), normals

    def geometric_normal(self, idx, found):
        """The unit geometric normal of the hit triangles where new rays leave along it (robust
        mode); None in course mode, whose rays leave along their own direction."""
        return None

    def _opaque_matrix(self, m: np.ndarray) -> list[list]:
        dr, F = self.dr, self.T.Float
        return [[dr.opaque(F, float(x)) for x in row] for row in m]

    def _as_records(self, rec: np.ndarray, ref_slots: tuple[int, ...]):
        """float32 records with uint32 bits in ref_slots as an aligned array of the render
        precision (in float64 the slots hold the integers' values, exact below 2^53)."""
        out = aligned_zeros(rec.shape, self.T.np_float)
        if self.T.precision == "single":
            out[:] = rec
        else:  # integer bits can be signalling NaNs as floats: never converted as floats
            floats = [k for k in range(rec.shape[1]) if k not in ref_slots]
            out[:, floats] = rec[:, floats]
            for k in ref_slots:
                out[:, k] = rec[:, k].view(np.uint32)
        return self.T.Float(out.ravel())

    # --- instances ------------------------------------------------------------------------
    def into_instance(self, inst, o, d):
        """The ray in instance `inst`'s space (unchanged where inst is NO_INSTANCE): through
        each level's M^-1 in turn, outermost first, as the course does (spec §5)."""
        dr, U = self.dr, self.T.UInt32
        valid = inst != NO_INSTANCE
        inst = dr.select(valid, inst, 0)
        count = dr.gather(U, self.inst_levels, inst, valid)
        for level in range(self.levels):
            row = (inst * self.levels + level) * 2
            a = gather_packet(self.T, self.inst_inverse, 8, row)
            b = gather_packet(self.T, self.inst_inverse, 8, row + 1)
            m = [[a[0], a[1], a[2], a[3]], [a[4], a[5], a[6], a[7]],
                 [b[0], b[1], b[2], b[3]], [b[4], b[5], b[6], b[7]]]
            o2, d2 = self.object_ray(m, o, d)
            use = valid & (count > level)
            o, d = dr.select(use, o2, o), dr.select(use, d2, d)
        return o, d

    def _to_world_normal(self, inst, n):
        """A hit normal of instance `inst` in world space: normalize(N·n) per level,
        innermost first."""
        dr, A3, U = self.dr, self.T.Array3f, self.T.UInt32
        if self.one_instance != NO_INSTANCE:  # every hit triangle is in that instance
            for options in reversed(self.one_normals):
                n = self.world_unit(self.through_level([
                    A3(*(dot(A3(*row), n) for row in rows)) for rows in options]))
            return n
        valid = inst != NO_INSTANCE
        inst = dr.select(valid, inst, 0)
        count = dr.gather(U, self.inst_levels, inst, valid)
        for level in reversed(range(self.levels)):
            base = (inst * self.levels + level) * 3
            through = []
            for normals in self.inst_normals:
                rows = [dr.gather(A3, normals, base + k, valid) for k in range(3)]
                through.append(A3(dot(rows[0], n), dot(rows[1], n), dot(rows[2], n)))
            n2 = self.world_unit(self.through_level(through))
            n = dr.select(valid & (count > level), n2, n)
        return n

    # --- queries --------------------------------------------------------------------------
    @staticmethod
    def _is_degenerate(d):
        """Whether the octree meets d degenerately (tracer.accel.octree): d normalized has a zero or
        NaN component, i.e. d has a zero component or |d|² is not finite. (A nonzero
        component that normalizing underflows to zero is taken as nonzero.)"""
        dr = import_drjit()
        return (d.x == 0.0) | (d.y == 0.0) | (d.z == 0.0) | ~dr.isfinite(dot(d, d))

    def _degenerate(self, d):
        """(lanes that may meet an octree degenerately, and their bit mask over the mesh
        spaces, bit k for mesh_instances[k]), or (None, None) without octrees. With more
        spaces than MAX_MESH_SPACES: every lane, and no mask."""
        dr, T = self.dr, self.T
        if not self.octrees:
            return None, None
        if len(self.mesh_instances) > MAX_MESH_SPACES:
            return dr.full(T.Bool, True, dr.width(d)), None
        bits = dr.zeros(T.UInt32, dr.width(d))
        for k, inst in enumerate(self.mesh_instances):
            dd = d
            if inst != NO_INSTANCE:
                for m in self.instances[inst].inverses:
                    dd = mat3_mul(m.tolist(), dd)
            bits |= dr.select(self._is_degenerate(dd), T.UInt32(1 << k), T.UInt32(0))
        return bits != 0, bits

    def _bvh_lanes(self, active, degenerate):
        if degenerate is None or not self.only_meshes:
            return active
        return ~degenerate if active is None else active & ~degenerate

    def search(self, o, d, t, order, active=None, candidates=None) -> "TriangleSearch":
        """The closest triangle closer than (t, order) along o + t·d; lanes outside `active`
        (if given) may skip it (their result is unspecified). candidates: (starts, triangles,
        list) of camera rays (screen_tiles.py): each lane tests the triangles of its list
        instead of searching the BVH."""
        T, dr = self.T, self.dr
        width = dr.width(o)
        state = TriangleSearch(t, order, dr.full(T.UInt32, NO_TRIANGLE, width),
                               dr.zeros(T.Float, width), dr.zeros(T.Float, width))
        deg, bits = self._degenerate(d)
        skip = self._skip_mesh(deg, bits)
        if self.bvh is None:
            state = self._brute_force(o, d, state, skip)
        elif candidates is not None:
            state = self._listed(o, d, state, candidates, self._bvh_lanes(active, deg), skip)
        else:
            state = traverse(self, o, d, state, None, self._bvh_lanes(active, deg), skip)
        if deg is not None:
            lanes = deg if active is None else deg & active
            state = self.octree.search(self._triangle, self._into, self._is_degenerate, o, d,
                                       state, self.torder, lanes, None)
        return state.with_file_order(self.dr, self.torder)

    def _skip_mesh(self, deg, bits):
        """What the BVH's triangle test gets to leave mesh triangles to the octree: None (no
        octrees, or no such lane enters the BVH), the lanes' bit masks over mesh spaces, or
        True (check each mesh triangle's direction in its own space)."""
        if deg is None or self.only_meshes:
            return None
        return True if bits is None else bits

    def _into(self, inst, o, d):
        return self.into_instance(inst, o, d) if self.instances else (o, d)

    def any_hit(self, o, d, limit, active=None, grid: "DeviceGrid | None" = None):
        """Whether some triangle is hit at a t <= limit (a negative limit: no lane needs it).
        grid: that of the rays' direction (shadow_grid.py, d the same in every lane): lanes
        near the triangles test their cell's list instead of searching the BVH."""
        T, dr = self.T, self.dr
        width = dr.width(o)
        state = TriangleSearch(dr.full(T.Float, FLT_MAX, width),
                               dr.full(T.UInt32, NO_TRIANGLE, width),
                               dr.full(T.UInt32, NO_TRIANGLE, width),
                               dr.zeros(T.Float, width), dr.zeros(T.Float, width))
        deg, bits = self._degenerate(d)
        skip = self._skip_mesh(deg, bits)
        if self.bvh is None:
            state = self._brute_force(o, d, state, skip)
            blocked = (state.tri != NO_TRIANGLE) & (state.t <= limit)
        else:
            lanes = self._bvh_lanes(active, deg)
            if grid is not None:
                state, near = self._grid_any(o, d, state, grid, limit, lanes, skip)
                lanes = ~near if lanes is None else lanes & ~near
            state = traverse(self, o, d, state, limit, lanes, skip)
            blocked = state.tri != NO_TRIANGLE  # both searches keep hits within the limit only
        if deg is not None:
            lanes = deg & ~blocked & (limit >= 0.0)
            lanes = lanes if active is None else lanes & active
            state = self.octree.search(self._triangle, self._into, self._is_degenerate, o, d,
                                       state, self.torder, lanes, limit)
            # t too: the brute-force search leaves its closest hit in the state, beyond the
            # limit or not
            blocked |= (state.tri != NO_TRIANGLE) & (state.t <= limit)
        return blocked

    def hit_data(self, state: "TriangleSearch", found, need_normal: bool):
        """(material, shading normal or None, geometric normal or None) of the hit triangles."""
        T, dr = self.T, self.dr
        A3, UInt32 = T.Array3f, T.UInt32
        idx = dr.select(found, state.tri, 0)
        mat = dr.gather(UInt32, self.tmaterial, idx, found)
        if not need_normal:
            return mat, None, None
        base = idx * 3
        n0 = dr.gather(A3, self.tnormals, base, found)
        n1 = dr.gather(A3, self.tnormals, base + 1, found)
        n2 = dr.gather(A3, self.tnormals, base + 2, found)
        n = self.shading_normal(idx, found, state.u, state.v, (n0, n1, n2))
        if self.instances:
            n = self._to_world_normal(dr.gather(UInt32, self.tinstance, idx, found), n)
        return mat, n, self.geometric_normal(idx, found)

    def shading_normal(self, idx, found, bu, bv, normals):
        """The shading normal of hit triangles idx at barycentric (bu, bv) from their vertex
        normals: interpolated and normalised (spec §5)."""
        one = self.site_constant(Site.TRIANGLE_WEIGHT0_ONE, 1.0)
        first = self.site_arithmetic(Site.TRIANGLE_WEIGHT0_U, one - bu, {
            Operator.PLUS: lambda: one + bu, Operator.TIMES: lambda: one * bu,
            Operator.DIVIDED: lambda: one / bu})
        w0 = self.site_arithmetic(Site.TRIANGLE_WEIGHT0_V, first - bv, {
            Operator.PLUS: lambda: first + bv, Operator.TIMES: lambda: first * bv,
            Operator.DIVIDED: lambda: first / bv})
        terms = (w0, bu, bv, 0.0, 1.0)  # the barycentric weights, as BARYCENTRIC
        w = [self.site_weight(site, terms) for site in WEIGHTS]
        n = [self.site_index(site, normals) for site in VERTICES]
        t = [self.site_arithmetic(site, w[k] * n[k], {
            Operator.PLUS: lambda k=k: w[k] + n[k], Operator.MINUS: lambda k=k: w[k] - n[k]})
            for k, site in enumerate(TERMS)]
        # C++'s precedence where the course's + is replaced: a * n0 * u * n1 is (a n0 u) n1
        pair = self.site_arithmetic(Site.TRIANGLE_SUM_1, t[0] + t[1], {
            Operator.MINUS: lambda: t[0] - t[1], Operator.TIMES: lambda: t[0] * w[1] * n[1],
            Operator.DIVIDED: lambda: t[0] / w[1] * n[1]})
        return self.unit(self.site_arithmetic(Site.TRIANGLE_SUM_2, pair + t[2], {
            Operator.MINUS: lambda: pair - t[2], Operator.TIMES: lambda: pair * w[2] * n[2],
            Operator.DIVIDED: lambda: pair / w[2] * n[2]}))

    def _triangle(self, i, o, d, skip_mesh=None, moved=False):
        """The course's triangle test (spec §5) against triangle i, in its instance's space:
        (t, u, v, accepted-before-the-closer-check). skip_mesh (see _skip_mesh): mesh
        triangles the octree decides are rejected. moved: (o, d) is already in the triangle's
        instance space."""
        T, dr = self.T, self.dr
        a = gather_packet(self.T, self.trecord, 8, i * 2)
        r = gather_packet(self.T, self.trecord, 8, i * 2 + 1)
        if self.instances and not moved:
            o, d = self.into_instance(dr.gather(T.UInt32, self.tinstance, i), o, d)
        n = T.Array3f(a[4], a[5], a[6])
        t = (a[3] - dot(o, n)) / dot(d, n)
        b = (o + t * d) - T.Array3f(a[0], a[1], a[2])
        bary = (dot(b, T.Array3f(r[0], r[1], r[2])), dot(b, T.Array3f(r[4], r[5], r[6])),
                dot(b, T.Array3f(a[7], r[3], r[7])))
        if self.site_compiled(Site.TRIANGLE_ORIGIN):
            # P - v1 = (P - v0) - e1, P - v2 = (P - v0) - e2: one coordinate one less
            bary = (bary[0] - self.site_index(Site.TRIANGLE_ORIGIN, (0.0, 1.0, 0.0)),
                    bary[1] - self.site_index(Site.TRIANGLE_ORIGIN, (0.0, 0.0, 1.0)), bary[2])
        u = self.site_index(Site.TRIANGLE_U_INDEX, bary)
        v = self.site_index(Site.TRIANGLE_V_INDEX, bary)
        w = bary[2]
        # the course compares |w| > 1e-3 in double: in float32, |w| >= float32(1e-3)
        # u > 1 and v > 1 reject no hit the others accept: where a program's do, it rejects
        # every hit or none, as TRIANGLE_ACCEPT or the course
        outside = ((dr.abs(w) >= TRIANGLE_W_TOLERANCE) | self._bound(Site.TRIANGLE_U_LOW, u, 0.0)
                   | (u > 1.0) | self._bound(Site.TRIANGLE_V_LOW, v, 0.0) | (v > 1.0)
                   | self._bound(Site.TRIANGLE_UV_SUM, u + v, 1.0))
        rejected = self.site_compare(Site.TRIANGLE_BEHIND, t, 0.0) | self.site_deleted(
            Site.TRIANGLE_INSIDE, outside, lambda: T.Bool(False))
        rejected = self.site_deleted(Site.TRIANGLE_ACCEPT, rejected,
                                     lambda: T.Bool(True))
        if skip_mesh is not None:
            space = dr.gather(T.UInt32, self.tspace, i)
            if skip_mesh is True:
                deg = self._is_degenerate(d)
            else:
                deg = ((skip_mesh >> dr.select(space != 0, space - 1, 0)) & 1) != 0
            rejected |= (space != 0) & deg
        return t, u, v, ~rejected

    def _bound(self, site: Site, x, course: float):
        """One of the tests that reject a hit outside the triangle: x OP bound."""
        return self.site_deleted(site, self.site_compare(site, x, self.site_constant(site, course)),
                                 lambda: self.T.Bool(False))

    def _brute_force(self, o, d, state: "TriangleSearch", skip_mesh=None) -> "TriangleSearch":
        dr, UInt32 = self.dr, self.T.UInt32

        def cond(i, _s):
            return i < self.tcount

        def body(i, s):
            t, u, v, ok = self._triangle(i, o, d, skip_mesh)
            s.offer(dr, ok, t, i, u, v, self.torder)
            return i + 1, s

        _, state = dr.while_loop((dr.zeros(UInt32, dr.width(o)), state), cond, body)
        return state

    def device_index(self) -> np.ndarray:
        """Each soup triangle's index on the device (the BVH's order)."""
        # asked for only with the BVH built (Renderer._screen_tiles checks)
        assert self.bvh is not None
        index = np.empty(self.count, np.int64)
        index[self.bvh.order] = np.arange(self.count)
        return index

    def _in_one_instance(self, o, d):
        """The ray in the space of the one instance all triangles are in (one_instance), as
        both searches take it; else as it is."""
        for m in self.one_inverses:
            o, d = self.object_ray(m, o, d)
        return o, d

    def _listed(self, o, d, state: "TriangleSearch", candidates, active, skip_mesh=None,
                limit=None, more=None) -> "TriangleSearch":
        """The closest hit among each lane's listed triangles (the BVH's test and offer, so
        the same hit where the list holds every triangle the ray can be accepted by); the
        ray moves into a single instance once, as the traversal moves it. With limit (an
        any-hit search): only hits within it count, and a lane stops at its first. more(k,
        end): whether a lane goes on to entry k of its list (default: k < end)."""
        dr, UInt32 = self.dr, self.T.UInt32
        starts, triangles, listed = candidates
        o, d = self._in_one_instance(o, d)
        moved = self.one_instance != NO_INSTANCE
        lanes = True if active is None else active
        first = dr.gather(UInt32, starts, listed, lanes)
        end = dr.select(lanes, dr.gather(UInt32, starts, listed + 1, lanes), first)
        more = more or (lambda k, end: k < end)

        def cond(k, go, _s):
            return go

        def body(k, go, s):
            i = dr.gather(UInt32, triangles, k)
            t, u, v, ok = self._triangle(i, o, d, skip_mesh, moved)
            if limit is not None:
                ok &= t <= limit
            s.offer(dr, ok, t, i, u, v, self.torder)
            go = more(k + 1, end)
            return k + 1, go if limit is None else go & ~ok, s

        _, _, state = dr.while_loop((first, more(first, end), state), cond, body)
        return state

    def _grid_any(self, o, d, state: "TriangleSearch", grid: DeviceGrid, limit, active,
                  skip_mesh=None) -> tuple["TriangleSearch", Any]:
        """(state, near): the first triangle of each near lane's cell that the BVH's test
        accepts within the limit, the cell's triangles tested highest first and none whose
        top lies below the ray's origin (shadow_grid.py); near: the lanes the grid answers
        (the others are left to the BVH)."""
        T, dr = self.T, self.dr
        origin, direction = self._in_one_instance(o, d)
        near, inside, cell = grid.cells(T, dr, origin)
        along = grid.along(dr, direction)  # the others go to the BVH
        near, inside = near & along, inside & along
        lanes = inside & (limit >= 0.0)  # a test accepts t >= 0 only
        lanes = lanes if active is None else lanes & active
        height = dot(origin, grid.w_axis)

        def above(k, end):
            go = k < end
            return go & (dr.gather(T.Float, grid.tops, k, go) >= height)

        state = self._listed(o, d, state, (grid.starts, grid.triangles, cell), lanes, skip_mesh,
                             limit, above)
        return state, near
