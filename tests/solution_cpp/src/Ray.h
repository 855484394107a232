#ifndef RAY_H
#define RAY_H

#include "vecmath.h"

// origin + t * direction; the direction is not necessarily unit length (rays in a Transform's
// child space keep the world's t)
class Ray {
public:
    Ray(const Vector3f& orig, const Vector3f& dir) : origin(orig), direction(dir) {}
    const Vector3f& getOrigin() const { return origin; }
    const Vector3f& getDirection() const { return direction; }
    Vector3f pointAtParameter(float t) const { return origin + t * direction; }
private:
    Vector3f origin;
    Vector3f direction;
};

#endif
