#ifndef HIT_H
#define HIT_H

#include <cfloat>
#include "vecmath.h"

class Material;

// the closest intersection found so far: t starts at FLT_MAX
class Hit {
public:
    Hit() : t(FLT_MAX), material(nullptr), normal(0, 0, 0) {}
    float getT() const { return t; }
    Material* getMaterial() const { return material; }
    const Vector3f& getNormal() const { return normal; }
    void set(float _t, Material* m, const Vector3f& n) { t = _t; material = m; normal = n; }
    void setNormal(const Vector3f& n) { normal = n; }
private:
    float t;
    Material* material;
    Vector3f normal;
};

#endif
