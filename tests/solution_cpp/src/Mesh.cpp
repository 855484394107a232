#include "Mesh.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

Mesh::Mesh(const std::string& filename, Material* m) : Object3D(m)
{
    std::ifstream f(filename);
    if (!f) {
        std::fprintf(stderr, "%s: cannot open the OBJ file\n", filename.c_str());
        std::exit(2);
    }
    std::vector<Vector3f> v;
    std::vector<int> faces;
    std::string line;
    int lineno = 0;
    while (std::getline(f, line)) {
        ++lineno;
        if (line.size() < 3 || line[0] == '#') {
            continue;
        }
        std::istringstream ss(line);
        std::string tag;
        ss >> tag;
        if (tag == "v") {
            std::string x, y, z;
            ss >> x >> y >> z;
            v.push_back(Vector3f(std::strtof(x.c_str(), nullptr), std::strtof(y.c_str(), nullptr),
                                 std::strtof(z.c_str(), nullptr)));
        } else if (tag == "f") {
            for (int k = 0; k < 3; ++k) {
                std::string index;
                ss >> index;  // "a" or "a/ta": the part after the slash is not used
                int i = std::atoi(index.c_str());
                if (i < 1 || i > (int)v.size()) {
                    std::fprintf(stderr, "%s:%d: face index out of range\n", filename.c_str(), lineno);
                    std::exit(2);
                }
                faces.push_back(i - 1);
            }
        }
    }
    if (faces.empty()) {
        std::fprintf(stderr, "%s: the OBJ file has no faces\n", filename.c_str());
        std::exit(2);
    }
    // each face adds its unit normal to its three vertices; the sums are normalised
    std::vector<Vector3f> n(v.size(), Vector3f(0, 0, 0));
    for (size_t i = 0; i < faces.size(); i += 3) {
        const Vector3f& a = v[faces[i]];
        Vector3f fn = Vector3f::cross(v[faces[i + 1]] - a, v[faces[i + 2]] - a).normalized();
        for (int k = 0; k < 3; ++k) n[faces[i + k]] += fn;
    }
    for (Vector3f& x : n) x = x.normalized();
    for (size_t i = 0; i < faces.size(); i += 3) {
        Triangle* t = new Triangle(v[faces[i]], v[faces[i + 1]], v[faces[i + 2]], material);
        for (int k = 0; k < 3; ++k) t->normals[k] = n[faces[i + k]];
        triangles.push_back(t);
    }
    octree.reset(new Octree(triangles));
}

Mesh::~Mesh()
{
    for (Triangle* t : triangles) delete t;
}

bool Mesh::intersect(const Ray& r, Hit& h, float tmin) const
{
    return octree->intersect(r, h, tmin);
}
