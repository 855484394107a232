#ifndef CAMERA_H
#define CAMERA_H

#include <cmath>
#include "Ray.h"
#include "vecmath.h"

class Camera {
public:
    virtual ~Camera() {}
    // point: (ndcx, ndcy) in [-1, 1]^2
    virtual Ray generateRay(const Vector2f& point) const = 0;
};

// The starter's camera: up is used as written (not orthogonalised), no aspect correction.
class PerspectiveCamera : public Camera {
public:
    PerspectiveCamera(const Vector3f& center, const Vector3f& direction, const Vector3f& up,
                      float angle)
        : center(center), w(direction.normalized()), u(Vector3f::cross(direction, up).normalized()),
          v(up), forward((1.0f / tanf(angle / 2.0f)) * w) {}

    Ray generateRay(const Vector2f& point) const override {
        Vector3f dir = (forward + point.x() * u) + point.y() * v;
        return Ray(center, dir.normalized());
    }
private:
    Vector3f center, w, u, v, forward;
};

#endif
