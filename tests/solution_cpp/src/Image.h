#ifndef IMAGE_H
#define IMAGE_H

#include <string>
#include <vector>

#include "vecmath.h"

// A float RGB image with PNG I/O. Pixel (x, y) has y = 0 at the BOTTOM, so
// the first row of a PNG file is y = h - 1 (for both saving and loading).
class Image {
public:
    Image(int w, int h);

    int getWidth() const { return w_; }
    int getHeight() const { return h_; }

    // Writes outside the image are ignored; reads are clamped to the edge.
    void setPixel(int x, int y, const Vector3f& color);
    Vector3f getPixel(int x, int y) const;

    // 8-bit RGB PNG. Returns false if the file cannot be written.
    bool savePNG(const std::string& path) const;

    // Reads 8-bit grey/RGB/palette/(grey|RGB)+alpha non-interlaced PNGs;
    // alpha is dropped. Returns nullptr (and says why on stderr) on failure.
    static Image* loadPNG(const std::string& path);

private:
    int w_, h_;
    std::vector<float> data_;  // RGB triples, row y = 0 first
};

#endif
