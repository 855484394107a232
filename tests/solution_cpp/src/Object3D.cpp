#include "Object3D.h"

#include <cmath>

Group::~Group()
{
    for (Object3D* obj : objects) {
        delete obj;
    }
}

bool Group::intersect(const Ray& r, Hit& h, float tmin) const
{
    bool result = false;
    for (Object3D* obj : objects) {
        result |= obj->intersect(r, h, tmin);
    }
    return result;
}

bool Sphere::intersect(const Ray& r, Hit& h, float tmin) const
{
    const Vector3f& d = r.getDirection();
    Vector3f oc = r.getOrigin() - _center;
    float a = Vector3f::dot(d, d);
    float b = 2.0f * Vector3f::dot(d, oc);
    float c = Vector3f::dot(oc, oc) - _radius * _radius;
    float disc = b * b - (4.0f * a) * c;
    if (disc < 0) {
        return false;
    }
    float root = std::sqrt(disc);
    float t0 = (-b - root) / (2.0f * a);
    float t1 = (-b + root) / (2.0f * a);
    if (t0 < tmin && t1 < tmin) {
        return false;
    }
    float t = 10000;
    if (t0 > tmin) {
        t = t0;
    } else if (t1 > tmin && t0 < tmin) {
        t = t1;
    }
    if (t < h.getT()) {
        Vector3f normal = (r.pointAtParameter(t) - _center).normalized();
        h.set(t, material, normal);
        return true;
    }
    return false;
}

Plane::Plane(const Vector3f& normal, float d, Material* m) : Object3D(m), _normal(normal), _d(d)
{
}

bool Plane::intersect(const Ray& r, Hit& h, float tmin) const
{
    float t = (_d - Vector3f::dot(r.getOrigin(), _normal)) / Vector3f::dot(r.getDirection(), _normal);
    if (t < tmin) {
        return false;
    }
    if (t < h.getT()) {
        h.set(t, material, _normal);
        return true;
    }
    return false;
}

bool Triangle::intersect(const Ray& r, Hit& h, float tmin) const
{
    Vector3f e1 = _v[1] - _v[0];
    Vector3f e2 = _v[2] - _v[0];
    Vector3f normal = Vector3f::cross(e1, e2).normalized();
    float d = Vector3f::dot(_v[0], normal);
    float t = (d - Vector3f::dot(r.getOrigin(), normal)) / Vector3f::dot(r.getDirection(), normal);
    if (t < tmin || !(t < h.getT())) {
        return false;
    }
    // barycentric coordinates of the plane hit: P - v0 = u e1 + v e2 + w N
    Matrix3f A(e1, e2, normal);
    Vector3f bary = A.inverse() * (r.pointAtParameter(t) - _v[0]);
    float u = bary[0], v = bary[1], w = bary[2];
    if (std::abs(w) > 1e-3 || u < 0 || u > 1 || v < 0 || v > 1 || u + v > 1) {
        return false;
    }
    Vector3f n = (((1.0f - u) - v) * normals[0] + u * normals[1]) + v * normals[2];
    h.set(t, material, n.normalized());
    return true;
}

Transform::Transform(const Matrix4f& m, Object3D* obj) : o(obj), _m(m)
{
}

bool Transform::intersect(const Ray& r, Hit& h, float tmin) const
{
    Matrix4f inv = _m.inverse();
    Vector4f o4 = inv * Vector4f(r.getOrigin(), 1.0f);
    Vector3f origin = o4.xyz() / o4.w();
    Vector3f dir = inv.getSubmatrix3x3(0, 0) * r.getDirection();
    if (!o->intersect(Ray(origin, dir), h, tmin)) {
        return false;
    }
    // normals go back with the inverse transpose of the matrix's own 3x3 part
    Matrix3f normalMatrix = _m.getSubmatrix3x3(0, 0).inverse().transposed();
    h.setNormal((normalMatrix * h.getNormal()).normalized());
    return true;
}
