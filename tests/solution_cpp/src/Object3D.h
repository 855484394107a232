#ifndef OBJECT3D_H
#define OBJECT3D_H

#include <vector>

#include "Hit.h"
#include "Material.h"
#include "Ray.h"
#include "vecmath.h"

// Every intersect replaces the hit only with a closer one (t < hit.getT()) and reports whether
// it did; tmin is the smallest t accepted.
class Object3D {
public:
    Object3D() : material(nullptr) {}
    explicit Object3D(Material* m) : material(m) {}
    virtual ~Object3D() {}
    virtual bool intersect(const Ray& r, Hit& h, float tmin) const = 0;
protected:
    Material* material;
};

class Group : public Object3D {
public:
    ~Group() override;
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
    void addObject(Object3D* obj) { objects.push_back(obj); }
    int getGroupSize() const { return (int)objects.size(); }
private:
    std::vector<Object3D*> objects;
};

class Sphere : public Object3D {
public:
    Sphere(const Vector3f& center, float radius, Material* m)
        : Object3D(m), _center(center), _radius(radius) {}
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
private:
    Vector3f _center;
    float _radius;
};

// the points p with p . normal = d
class Plane : public Object3D {
public:
    Plane(const Vector3f& normal, float d, Material* m);
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
private:
    Vector3f _normal;
    float _d;
};

class Triangle : public Object3D {
public:
    // a, b, c: the vertices; normals[i]: the shading normal at vertex i
    Triangle(const Vector3f& a, const Vector3f& b, const Vector3f& c, Material* m)
        : Object3D(m) { _v[0] = a; _v[1] = b; _v[2] = c; }
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
    const Vector3f& getVertex(int i) const { return _v[i]; }
    Vector3f normals[3];
private:
    Vector3f _v[3];
};

// m maps the child's space to the parent's
class Transform : public Object3D {
public:
    Transform(const Matrix4f& m, Object3D* obj);
    ~Transform() override { delete o; }
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
private:
    Object3D* o;
    Matrix4f _m;
};

#endif
