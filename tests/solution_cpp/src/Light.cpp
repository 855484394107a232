#include "Light.h"

#include <cfloat>

void DirectionalLight::getIllumination(const Vector3f& p, Vector3f& tolight, Vector3f& intensity,
                                       float& distToLight) const
{
    // the light is infinitely far away: every blocker counts
    distToLight = FLT_MAX;
    tolight = -_direction;
    intensity = _color;
}

void PointLight::getIllumination(const Vector3f& p, Vector3f& tolight, Vector3f& intensity,
                                 float& distToLight) const
{
    Vector3f toLight = _position - p;
    distToLight = toLight.abs();
    tolight = toLight / distToLight;
    // the intensity falls off with the squared distance
    intensity = _color / ((distToLight * _falloff) * distToLight);
}
