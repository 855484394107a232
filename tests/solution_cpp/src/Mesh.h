#ifndef MESH_H
#define MESH_H

#include <memory>
#include <string>
#include <vector>

#include "Object3D.h"
#include "Octree.h"

// A triangle mesh from an OBJ file, shaded smooth by vertex normals the loader computes
// (the file's own normals are not used), intersected through an octree.
class Mesh : public Object3D {
public:
    Mesh(const std::string& filename, Material* m);
    ~Mesh() override;
    bool intersect(const Ray& r, Hit& h, float tmin) const override;
private:
    std::vector<Triangle*> triangles;
    std::unique_ptr<Octree> octree;
};

#endif
