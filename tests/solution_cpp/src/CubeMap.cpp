#include "CubeMap.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <xmmintrin.h>

namespace {

// C's float-to-int conversion as the x86 instruction does it (NaN and overflow: INT_MIN),
// without the undefined behaviour of a cast
int truncate(float x)
{
    return _mm_cvttss_si32(_mm_set_ss(x));
}

int clampIndex(int i, int n)
{
    return i < 0 ? 0 : (i > n - 1 ? n - 1 : i);
}

}  // namespace

CubeMap::CubeMap(const std::string& directory)
{
    const char* names[6] = {"right", "left", "up", "down", "front", "back"};
    for (int k = 0; k < 6; ++k) {
        std::string path = directory + "/" + names[k] + ".png";
        faces[k].reset(Image::loadPNG(path));
        if (!faces[k]) {
            std::exit(2);  // loadPNG said why
        }
    }
}

// texel (i, j) of a face, j counted from the top row of the file
Vector3f CubeMap::texel(int face, int i, int j) const
{
    const Image& im = *faces[face];
    return im.getPixel(i, im.getHeight() - 1 - j);
}

Vector3f CubeMap::operator()(const Vector3f& direction) const
{
    Vector3f n = direction.normalized();
    float ax = std::fabs(n.x()), ay = std::fabs(n.y()), az = std::fabs(n.z());
    bool useX = ax >= ay && ax >= az;
    bool useY = !useX && ay >= az;
    bool useZ = !useX && !useY;
    float major = useX ? n.x() : (useY ? n.y() : n.z());
    if (major == 0) {
        return Vector3f(0, 0, 0);
    }
    float first = useX ? n.z() : n.x();
    float second = useY ? n.z() : n.y();
    float p = (first / major + 1.0f) * 0.5f;
    float q = (second / major + 1.0f) * 0.5f;
    bool positive = major > 0;
    float u = ((useY && !positive) || (useZ && positive)) ? 1.0f - p : p;
    float v = positive ? q : 1.0f - q;
    int face = useX ? (positive ? RIGHT : LEFT)
                    : (useY ? (positive ? UP : DOWN) : (positive ? FRONT : BACK));
    int w = faces[face]->getWidth(), h = faces[face]->getHeight();
    float x = u * (float)w;
    float y = (1.0f - v) * (float)h;
    int xi = truncate(x), yi = truncate(y);
    float a = x - (float)xi, b = y - (float)yi;
    int i0 = clampIndex(xi, w), i1 = clampIndex(xi + 1, w);
    int j0 = clampIndex(yi, h), j1 = clampIndex(yi + 1, h);
    return ((texel(face, i0, j0) * ((1.0f - a) * (1.0f - b)) + texel(face, i1, j0) * (a * (1.0f - b)))
            + texel(face, i0, j1) * ((1.0f - a) * b))
           + texel(face, i1, j1) * (a * b);
}
