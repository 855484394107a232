#ifndef CUBEMAP_H
#define CUBEMAP_H

#include <memory>
#include <string>

#include "Image.h"
#include "vecmath.h"

// Six faces (left right up down front back .png in a folder), looked up by direction with
// bilinear filtering.
class CubeMap {
public:
    enum Face { RIGHT, LEFT, UP, DOWN, FRONT, BACK };
    explicit CubeMap(const std::string& directory);
    Vector3f operator()(const Vector3f& direction) const;
private:
    Vector3f texel(int face, int i, int j) const;
    std::unique_ptr<Image> faces[6];
};

#endif
