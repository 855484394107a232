#ifndef MATERIAL_H
#define MATERIAL_H

#include "Hit.h"
#include "Ray.h"
#include "vecmath.h"

class Material {
public:
    Material(const Vector3f& d, const Vector3f& s = Vector3f(0, 0, 0), float sh = 0)
        : _diffuseColor(d), _specularColor(s), _shininess(sh) {}
    const Vector3f& getDiffuseColor() const { return _diffuseColor; }
    const Vector3f& getSpecularColor() const { return _specularColor; }
    float getShininess() const { return _shininess; }

    // the Phong terms of one light (direction dirToLight, color lightIntensity) at the hit
    Vector3f shade(const Ray& ray, const Hit& hit, const Vector3f& dirToLight,
                   const Vector3f& lightIntensity);
private:
    Vector3f _diffuseColor;
    Vector3f _specularColor;
    float _shininess;
};

#endif
