"""The course's octree traversal (Revelles et al., "An efficient parametric algorithm for octree
traversal", 2000) as one Dr.Jit loop, for the rays it traverses degenerately (tracer.accel.octree).

Per mesh, the course normalizes the ray direction, mirrors the axes where it is negative (the
origin becomes lo + hi - o there, and the child index is XORed with the mirror bits a), and
computes the slab parameters t0 = (lo - o)/d, t1 = (hi - o)/d as (lo - o)·(1/d). The root is
entered when min(t1) >= max(t0) with std::min/std::max (which keep their first argument when a
comparison with NaN fails). A node is skipped when some t1 < 0; a leaf tests its triangles with
the ray itself (closest hit, no early exit); an inner node visits children from
first_node(t0, tm), tm = 0.5·(t0 + t1), stepping with new_node. With a zero direction
component, 1/d is inf, t0 or t1 may be NaN, tm is NaN, and the traversal never enters the
upper half along that axis: this is what the course's images show, so it is reproduced
comparison for comparison here.

The recursion is an explicit per-lane stack of frames (the node's first child, t0, t1, the
child to visit next); each loop step does one of: start the next mesh, enter a requested
node, test one pending leaf triangle, or take the next child of the top frame.
"""
from __future__ import annotations

import numpy as np

from ..kernel.backend import from_numpy, import_drjit, syntax_on_first_call
from ..kernel.vecmath import Types, normalize
from .octree import INNER, MAX_LEVEL, Octree

STACK = MAX_LEVEL + 1  # frames per lane: one per inner level
AXIS_BITS = (4, 2, 1)  # child-number bit of the upper half along x, y, z


def _std_max(dr, a, b):
    return dr.select(a < b, b, a)


def _std_min(dr, a, b):
    return dr.select(b < a, b, a)


class OctreeTraversal:
    def __init__(self, meshes: list[tuple[Octree, np.ndarray, int]], types: Types) -> None:
        """meshes: per TriangleMesh, its octree, the record number of each of its triangles
        and its instance (NO_INSTANCE: untransformed)."""
        self.T = types
        self.dr = import_drjit()
        nodes, tris, lo, hi, roots, insts = [], [], [], [], [], []
        node_base = tri_base = 0
        for tree, records, inst in meshes:
            insts.append(inst)
            rec = tree.nodes.astype(np.int64)
            inner = rec[:, 1] == INNER
            rec[inner, 0] += node_base
            rec[~inner, 0] += tri_base
            nodes.append(rec.astype(np.uint32))
            tris.append(records[tree.tris].astype(np.uint32))
            lo.append(tree.lo)
            hi.append(tree.hi)
            roots.append(node_base)
            node_base += len(rec)
            tri_base += len(tree.tris)
        T = types
        self.nodes = T.UInt32(np.concatenate(nodes).ravel())
        self.tris = T.UInt32(np.concatenate(tris)) if tri_base else T.UInt32([0])
        self.lo = T.Float(np.array(lo, np.float32).ravel())
        self.hi = T.Float(np.array(hi, np.float32).ravel())
        self.roots = from_numpy(T.UInt32, np.array(roots, np.uint32))  # one a mesh
        self.instance = from_numpy(T.UInt32, np.array(insts, np.uint32))
        self.mesh_count = self.dr.opaque(T.UInt32, len(meshes))

    def _first_node(self, t0, tm):
        dr, U = self.dr, self.T.UInt32
        x0, y0, z0 = t0
        xm, ym, zm = tm

        def bit(cond, value):
            return dr.select(cond, U(value), U(0))

        yz = (x0 > y0) & (x0 > z0)
        xz = ~(x0 > y0) & (y0 > z0)
        return dr.select(yz, bit(x0 > ym, 2) | bit(x0 > zm, 1),
                         dr.select(xz, bit(y0 > xm, 4) | bit(y0 > zm, 1),
                                   bit(z0 > xm, 4) | bit(z0 > ym, 2)))

    def _new_node(self, e, codes):
        dr = self.dr
        (ex, ey, ez), (cx, cy, cz) = e, codes
        return dr.select(ey > ex, dr.select(ez > ex, cx, cz), dr.select(ez > ey, cy, cz))

    def search(self, test, into, is_degenerate, o, d, state, torder, active, any_hit_limit):
        """The closest hit over the triangles the course's octrees test for these rays,
        offered to `state` (a TriangleSearch, with the file order per record `torder`)
        through test(record, o, d) -> (t, u, v, ok) with the world ray; into(instance, o, d)
        gives the ray in a mesh's space. Meshes whose ray is not is_degenerate(d) are the
        BVH's and skipped here. With any_hit_limit, only hits at t <= limit, stopping at the
        first. Lanes outside `active` are left as they are."""
        return self._loop(test, into, is_degenerate, o, d, state, torder, self.T.Bool(active),
                          any_hit_limit)

    def _mesh_ray(self, into, is_degenerate, mesh, o, d, begin):
        """A mesh's ray as its octree takes it: the mirror bits a, which axes are mirrored,
        1/|d̂| per axis and the object-space origin, and whether d̂ has a zero component."""
        dr, U = self.dr, self.T.UInt32
        om, dm = into(dr.gather(U, self.instance, mesh, begin), o, d)
        dn = normalize(dm)
        comps = [dn.x, dn.y, dn.z]
        neg = [c < 0.0 for c in comps]
        a = ((dr.select(neg[0], U(4), U(0)) | dr.select(neg[1], U(2), U(0)))
             | dr.select(neg[2], U(1), U(0)))
        inv = [1.0 / dr.select(neg[k], -comps[k], comps[k]) for k in range(3)]
        return a, neg, inv, [om.x, om.y, om.z], is_degenerate(dm)

    @syntax_on_first_call
    def _loop(self, test, into, is_degenerate, o, d, state, torder, active, any_hit_limit):
        # Every step is masked (no symbolic ifs but TriangleSearch.offer's branch for ties in
        # t): only packets holding such rays run this.
        # No dataclass locals here (such as self.T): @dr.syntax would treat them as loop state.
        dr = self.dr
        U, F, B = self.T.UInt32, self.T.Float, self.T.Bool
        width = dr.width(o)
        node_st = dr.alloc_local(U, STACK)  # first child of the frame's node
        cur_st = dr.alloc_local(U, STACK)  # the frame's next child (8: none left)
        t_st = [dr.alloc_local(F, STACK) for _ in range(6)]  # the frame's t0.xyz, t1.xyz
        mesh = dr.zeros(U, width)  # mesh being traversed
        a = dr.zeros(U, width)  # its mirror bits
        sp = dr.zeros(U, width)  # frames on the stack
        tri = dr.zeros(U, width)  # pending leaf triangles: tri .. tri_end - 1
        tri_end = dr.zeros(U, width)
        req_node = dr.zeros(U, width)  # node to enter next, with req_t = (t0, t1)
        req_t = [dr.zeros(F, width) for _ in range(6)]
        req = dr.full(B, False, width)
        start = B(active)  # the next mesh's root is to be tested
        done = dr.full(B, False, width)  # any-hit: found one
        live = B(active)
        while live:
            begin = live & start
            enter = live & ~start & req
            idle = live & ~start & ~req & (tri >= tri_end)
            leaf_step = live & ~start & ~req & (tri < tri_end)
            frame = idle & (sp > 0)
            advance = idle & (sp == 0)

            # start a mesh: its ray, mirrored origin, slab parameters, root test
            m_a, m_neg, m_inv, m_o, m_deg = self._mesh_ray(into, is_degenerate, mesh, o, d, begin)
            lo = [dr.gather(F, self.lo, mesh * 3 + k, begin) for k in range(3)]
            hi = [dr.gather(F, self.hi, mesh * 3 + k, begin) for k in range(3)]
            om = [dr.select(m_neg[k], (lo[k] + hi[k]) - m_o[k], m_o[k]) for k in range(3)]
            t0 = [(lo[k] - om[k]) * m_inv[k] for k in range(3)]
            t1 = [(hi[k] - om[k]) * m_inv[k] for k in range(3)]
            root_in = m_deg & (_std_min(dr, _std_min(dr, t1[0], t1[1]), t1[2])
                               >= _std_max(dr, _std_max(dr, t0[0], t0[1]), t0[2]))
            a = dr.select(begin, m_a, a)

            # enter the requested node: skipped, its triangles pending, or a new frame
            skip = (req_t[3] < 0.0) | (req_t[4] < 0.0) | (req_t[5] < 0.0)
            rec0 = dr.gather(U, self.nodes, req_node * 2, enter)
            rec1 = dr.gather(U, self.nodes, req_node * 2 + 1, enter)
            to_leaf = enter & ~skip & (rec1 != INNER)
            push = enter & ~skip & (rec1 == INNER)
            tm = [0.5 * (req_t[k] + req_t[k + 3]) for k in range(3)]
            node_st.write(rec0, sp, push)
            cur_st.write(self._first_node(req_t[:3], tm), sp, push)
            for k in range(6):
                t_st[k].write(req_t[k], sp, push)
            tri = dr.select(to_leaf, rec0, tri)
            tri_end = dr.select(to_leaf, rec0 + rec1, tri_end)

            # one pending leaf triangle, tested with the ray itself
            rec = dr.gather(U, self.tris, tri, leaf_step)
            t, u, v, ok = test(rec, o, d)
            ok &= leaf_step
            if any_hit_limit is not None:
                ok &= t <= any_hit_limit
                done |= ok
            state.offer(dr, ok, t, rec, u, v, torder)

            # the top frame: pop it, or request its next child and step its cursor
            top = dr.select(sp > 0, sp - 1, 0)
            cur = cur_st.read(top)
            step = frame & (cur < 8)
            ft = [t_st[k].read(top) for k in range(6)]
            fm = [0.5 * (ft[k] + ft[k + 3]) for k in range(3)]
            up = [(cur & AXIS_BITS[k]) != 0 for k in range(3)]
            c0 = [dr.select(up[k], fm[k], ft[k]) for k in range(3)]
            c1 = [dr.select(up[k], ft[k + 3], fm[k]) for k in range(3)]
            codes = [dr.select(up[k], U(8), cur | AXIS_BITS[k]) for k in range(3)]
            cur_st.write(self._new_node(c1, codes), top, step)
            child = node_st.read(top) + (cur ^ a)

            req_node = dr.select(begin, dr.gather(U, self.roots, mesh, begin),
                                 dr.select(step, child, req_node))
            root_t, child_t = t0 + t1, c0 + c1
            req_t = [dr.select(begin, root_t[k], dr.select(step, child_t[k], req_t[k]))
                     for k in range(6)]
            req = dr.select(begin, root_in, dr.select(step, True, req & ~enter))
            sp = dr.select(push, sp + 1, dr.select(frame & (cur >= 8), sp - 1, sp))
            tri = dr.select(leaf_step, tri + 1, tri)
            mesh = dr.select(advance, mesh + 1, mesh)
            start = (start & ~begin) | (advance & (mesh < self.mesh_count))
            live = live & ~done & (mesh < self.mesh_count)
        return state
