#ifndef OCTREE_H
#define OCTREE_H

#include <vector>

#include "Hit.h"
#include "Ray.h"
#include "vecmath.h"

class Triangle;

// The starter's mesh octree: built over a mesh's triangles in the mesh's space, traversed with
// Revelles et al.'s parametric algorithm ("An efficient parametric algorithm for octree
// traversal", 2000).
class Octree {
public:
    static const int MAX_LEVEL = 8;
    static const int LEAF_SIZE = 7;

    explicit Octree(const std::vector<Triangle*>& triangles);
    bool intersect(const Ray& r, Hit& h, float tmin) const;
private:
    struct Node {
        int child = -1;               // first of the eight children, -1 for a leaf
        std::vector<int> triangles;  // a leaf's triangles
    };
    void build(int node, const Vector3f& lo, const Vector3f& hi, int level,
               const std::vector<int>& tris);
    // a: the child-number bits of the axes the ray's direction was mirrored on
    bool visit(int node, const float t0[3], const float t1[3], int a, const Ray& r, Hit& h,
               float tmin) const;

    const std::vector<Triangle*>& tris;
    std::vector<Node> nodes;
    std::vector<Vector3f> triLo, triHi;
    Vector3f lo, hi;
};

#endif
