#ifndef LIGHT_H
#define LIGHT_H

#include "vecmath.h"

class Light {
public:
    virtual ~Light() {}
    // p: a point in the scene; tolight: the unit direction from p toward the light;
    // intensity: the light's color arriving at p; distToLight: the distance to the light
    virtual void getIllumination(const Vector3f& p, Vector3f& tolight, Vector3f& intensity,
                                 float& distToLight) const = 0;
};

class DirectionalLight : public Light {
public:
    // direction: where the light travels (normalised by the parser)
    DirectionalLight(const Vector3f& d, const Vector3f& c) : _direction(d), _color(c) {}
    void getIllumination(const Vector3f& p, Vector3f& tolight, Vector3f& intensity,
                         float& distToLight) const override;
private:
    Vector3f _direction;
    Vector3f _color;
};

class PointLight : public Light {
public:
    PointLight(const Vector3f& p, const Vector3f& c, float fall)
        : _position(p), _color(c), _falloff(fall) {}
    void getIllumination(const Vector3f& p, Vector3f& tolight, Vector3f& intensity,
                         float& distToLight) const override;
private:
    Vector3f _position;
    Vector3f _color;
    float _falloff;
};

#endif
