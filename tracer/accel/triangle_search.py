"""The state of a closest-hit or any-hit search over a TriangleSet's triangles: the best hit
so far, and how a candidate is offered to it (closer wins, a tie goes to file order)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

NO_TRIANGLE = 0xFFFFFFFF


@dataclass
class TriangleSearch:
    """The best triangle hit so far in a closest-hit search (a Dr.Jit PyTree). `order` is the
    file order of the best hit while that is not one of the set's triangles (tri is
    NO_TRIANGLE: the hit the search started from); a triangle's own order is read from the
    set's file-order array only where two hits tie in t, and once at the end
    (with_file_order)."""

    # Defaults because Dr.Jit rebuilds PyTrees with an argument-less constructor.
    t: Any = None
    order: Any = None
    tri: Any = None
    u: Any = None
    v: Any = None
    DRJIT_STRUCT = {"t": object, "order": object, "tri": object, "u": object, "v": object}

    def offer(self, dr, ok, t, tri, u, v, torder) -> None:
        """Take the candidate triangle if accepted and closer; equal t goes to the earlier
        primitive in file order (torder: the set's file order per triangle). The tie test is
        a branch that packets without a tie skip."""
        def earlier(tie, tri, best_tri, best_order):
            mine = dr.gather(type(tri), torder, tri, tie)
            has_best = tie & (best_tri != NO_TRIANGLE)
            best = dr.select(has_best, dr.gather(type(tri), torder, best_tri, has_best),
                             best_order)
            return tie & (mine < best)

        def no_tie(tie, tri, best_tri, best_order):
            return dr.zeros(type(tie), dr.width(tie))

        tie = ok & (t == self.t)
        take = (ok & (t < self.t)) | dr.if_stmt((tie, tri, self.tri, self.order), tie, earlier,
                                                no_tie)
        self.t = dr.select(take, t, self.t)
        self.tri = dr.select(take, tri, self.tri)
        self.u = dr.select(take, u, self.u)
        self.v = dr.select(take, v, self.v)

    def with_file_order(self, dr, torder) -> "TriangleSearch":
        """The search with `order` the best hit's file order, a triangle's too."""
        found = self.tri != NO_TRIANGLE
        self.order = dr.select(found, dr.gather(type(self.tri), torder, self.tri, found),
                               self.order)
        return self
