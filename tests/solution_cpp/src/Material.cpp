#include "Material.h"

#include <cmath>

Vector3f Material::shade(const Ray& ray, const Hit& hit, const Vector3f& dirToLight,
                         const Vector3f& lightIntensity)
{
    const Vector3f& n = hit.getNormal();
    float diffuse = Vector3f::dot(n, dirToLight);
    if (diffuse < 0) {
        diffuse = 0;
    }
    // the eye ray mirrored about the normal
    const Vector3f& d = ray.getDirection();
    Vector3f r = d - (2.0f * Vector3f::dot(n, d)) * n;
    float specular = Vector3f::dot(r, dirToLight);
    if (specular < 0) {
        specular = 0;
    }
    Vector3f kd = (diffuse * lightIntensity) * _diffuseColor;
    Vector3f ks = (powf(specular, _shininess) * lightIntensity) * _specularColor;
    return kd + ks;
}
