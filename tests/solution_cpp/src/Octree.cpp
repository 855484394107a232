#include "Octree.h"

#include <algorithm>

#include "Object3D.h"

namespace {

const int AXIS_BIT[3] = {4, 2, 1};

int firstNode(const float t0[3], const float tm[3])
{
    if (t0[0] > t0[1] && t0[0] > t0[2]) {
        return (t0[0] > tm[1] ? 2 : 0) | (t0[0] > tm[2] ? 1 : 0);
    }
    if (!(t0[0] > t0[1]) && t0[1] > t0[2]) {
        return (t0[1] > tm[0] ? 4 : 0) | (t0[1] > tm[2] ? 1 : 0);
    }
    return (t0[2] > tm[0] ? 4 : 0) | (t0[2] > tm[1] ? 2 : 0);
}

// the child the ray enters next: the one across the axis it leaves first (8: none)
int newNode(const float e[3], const int code[3])
{
    if (e[1] > e[0]) {
        return e[2] > e[0] ? code[0] : code[2];
    }
    return e[2] > e[1] ? code[1] : code[2];
}

}  // namespace

Octree::Octree(const std::vector<Triangle*>& triangles) : tris(triangles)
{
    for (Triangle* t : tris) {
        Vector3f a = t->getVertex(0), b = a;
        for (int k = 1; k < 3; ++k) {
            const Vector3f& v = t->getVertex(k);
            for (int i = 0; i < 3; ++i) {
                if (a[i] > v[i]) a[i] = v[i];
                if (v[i] > b[i]) b[i] = v[i];
            }
        }
        triLo.push_back(a);
        triHi.push_back(b);
    }
    lo = tris[0]->getVertex(0);
    hi = lo;
    for (Triangle* t : tris) {
        for (int k = 0; k < 3; ++k) {
            const Vector3f& v = t->getVertex(k);
            for (int i = 0; i < 3; ++i) {
                if (lo[i] > v[i]) lo[i] = v[i];
                if (v[i] > hi[i]) hi[i] = v[i];
            }
        }
    }
    std::vector<int> all(tris.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = (int)i;
    nodes.emplace_back();
    build(0, lo, hi, 0, all);
}

void Octree::build(int node, const Vector3f& blo, const Vector3f& bhi, int level,
                   const std::vector<int>& list)
{
    if ((int)list.size() <= LEAF_SIZE || level >= MAX_LEVEL) {
        nodes[node].triangles = list;
        return;
    }
    int first = (int)nodes.size();
    nodes[node].child = first;
    nodes.resize(first + 8);
    Vector3f mid = (blo + bhi) / 2.0f;
    for (int j = 0; j < 8; ++j) {
        Vector3f clo, chi;
        for (int i = 0; i < 3; ++i) {
            bool upper = (j & AXIS_BIT[i]) != 0;
            clo[i] = upper ? mid[i] : blo[i];
            chi[i] = upper ? bhi[i] : mid[i];
        }
        std::vector<int> inside;
        for (int t : list) {
            bool contained = true, overlaps = true;
            for (int i = 0; i < 3; ++i) {
                contained = contained && !(clo[i] > triLo[t][i]) && !(triHi[t][i] > chi[i]);
                overlaps = overlaps && !(triLo[t][i] > chi[i]) && triHi[t][i] >= clo[i];
            }
            if (contained || overlaps) inside.push_back(t);
        }
        build(first + j, clo, chi, level + 1, inside);
    }
}

bool Octree::intersect(const Ray& r, Hit& h, float tmin) const
{
    Vector3f d = r.getDirection().normalized();
    Vector3f o = r.getOrigin();
    int a = 0;
    for (int i = 0; i < 3; ++i) {
        if (d[i] < 0) {
            o[i] = (lo[i] + hi[i]) - o[i];
            d[i] = -d[i];
            a |= AXIS_BIT[i];
        }
    }
    float t0[3], t1[3];
    for (int i = 0; i < 3; ++i) {
        float inv = 1.0f / d[i];
        t0[i] = (lo[i] - o[i]) * inv;
        t1[i] = (hi[i] - o[i]) * inv;
    }
    if (!(std::min(std::min(t1[0], t1[1]), t1[2]) >= std::max(std::max(t0[0], t0[1]), t0[2]))) {
        return false;
    }
    return visit(0, t0, t1, a, r, h, tmin);
}

bool Octree::visit(int node, const float t0[3], const float t1[3], int a, const Ray& r, Hit& h,
                   float tmin) const
{
    if (t1[0] < 0 || t1[1] < 0 || t1[2] < 0) {
        return false;
    }
    const Node& n = nodes[node];
    bool found = false;
    if (n.child < 0) {
        for (int t : n.triangles) {
            found |= tris[t]->intersect(r, h, tmin);
        }
        return found;
    }
    float tm[3];
    for (int i = 0; i < 3; ++i) tm[i] = 0.5f * (t0[i] + t1[i]);
    int cur = firstNode(t0, tm);
    do {
        float c0[3], c1[3];
        int code[3];
        for (int i = 0; i < 3; ++i) {
            bool upper = (cur & AXIS_BIT[i]) != 0;
            c0[i] = upper ? tm[i] : t0[i];
            c1[i] = upper ? t1[i] : tm[i];
            code[i] = upper ? 8 : (cur | AXIS_BIT[i]);
        }
        found |= visit(n.child + (cur ^ a), c0, c1, a, r, h, tmin);
        cur = newNode(c1, code);
    } while (cur < 8);
    return found;
}
