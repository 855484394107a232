"""Intersection: the scene flattened into spheres, planes and one triangle soup (flat_scene,
with float32 matrix inverses as the course computes them: matrices), closest-hit and shadow
queries over it (intersect), the triangles on the device with the course's test (triangles),
the BVH (bvh: its build; wide_bvh: its four-wide layout; wide_traversal: the node tests),
the course's mesh octrees (octree, octree_traversal), shadow grids (shadow_grid) and camera
rays' screen tiles (screen_tiles)."""
