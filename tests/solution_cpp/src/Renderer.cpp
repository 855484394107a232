#include "Renderer.h"

#include <cstdio>
#include <random>
#include <vector>

#include "Camera.h"
#include "Image.h"

Renderer::Renderer(const ArgParser& args) : _args(args), _scene(args.input_file)
{
}

void Renderer::Render()
{
    const int k = _args.filter ? 3 : 1;  // -filter renders at three times the size
    const int w = _args.width * k, h = _args.height * k;
    const int samples = _args.jitter ? 16 : 1;
    const float range = _args.depth_max - _args.depth_min;
    std::vector<Vector3f> color(w * h), normals(w * h), depth(w * h);
    // -jitter: sample offsets uniform in [0, 1) of a (sub-)pixel
    std::mt19937 rng(837);
    auto uniform = [&rng]() { return (float)(rng() >> 8) * (1.0f / 16777216.0f); };
    Camera* camera = _scene.getCamera();
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            Vector3f c(0, 0, 0), n(0, 0, 0);
            float d = 0;
            for (int s = 0; s < samples; ++s) {
                float sx = (float)x, sy = (float)y;
                if (_args.jitter) {
                    sx += uniform();
                    sy += uniform();
                }
                float ndcx = 2 * (sx / (w - 1.0f)) - 1;
                float ndcy = 2 * (sy / (h - 1.0f)) - 1;
                Ray r = camera->generateRay(Vector2f(ndcx, ndcy));
                Hit hit;
                c += traceRay(r, 0, _args.bounces, hit);
                n += (hit.getNormal() + Vector3f(1, 1, 1)) / 2.0f;
                d += (hit.getT() - _args.depth_min) / range;
            }
            color[y * w + x] = c / (float)samples;
            normals[y * w + x] = n / (float)samples;
            depth[y * w + x] = Vector3f(d / (float)samples);
        }
    }
    const float weight[3][3] = {{1, 2, 1}, {2, 4, 2}, {1, 2, 1}};
    auto write = [&](const std::vector<Vector3f>& big, const std::string& file) {
        if (file.empty()) return;
        Image image(_args.width, _args.height);
        for (int y = 0; y < _args.height; ++y) {
            for (int x = 0; x < _args.width; ++x) {
                if (k == 1) {
                    image.setPixel(x, y, big[y * w + x]);
                    continue;
                }
                // a Gaussian of the 3x3 sub-pixels
                Vector3f sum = big[(3 * y) * w + 3 * x] * weight[0][0];
                for (int j = 0; j < 3; ++j) {
                    for (int i = (j == 0 ? 1 : 0); i < 3; ++i) {
                        sum += big[(3 * y + j) * w + 3 * x + i] * weight[j][i];
                    }
                }
                image.setPixel(x, y, sum / 16.0f);
            }
        }
        if (!image.savePNG(file)) {
            std::fprintf(stderr, "a2: cannot write %s\n", file.c_str());
            std::exit(1);
        }
    };
    write(color, _args.output_file);
    write(normals, _args.normals_file);
    write(depth, _args.depth_file);
}

Vector3f Renderer::traceRay(const Ray& r, float tmin, int bounces, Hit& h) const
{
    Group* group = _scene.getGroup();
    if (!group->intersect(r, h, tmin)) {
        return _scene.getBackgroundColor(r.getDirection());
    }
    Vector3f p = r.pointAtParameter(h.getT());
    Material* m = h.getMaterial();
    Vector3f color(0, 0, 0);
    for (int i = 0; i < _scene.getNumLights(); ++i) {
        Vector3f tolight, intensity;
        float distToLight;
        _scene.getLight(i)->getIllumination(p, tolight, intensity, distToLight);
        if (_args.shadows) {
            // start a little off the surface, or the surface shadows itself
            Ray shadowRay(p + 0.01f * tolight, tolight);
            Hit shadowHit;
            if (group->intersect(shadowRay, shadowHit, 0) && !(shadowHit.getT() > distToLight)) {
                continue;
            }
        }
        color += m->shade(r, h, tolight, intensity);
    }
    const Vector3f& ks = m->getSpecularColor();
    if (bounces > 0 && ks.abs() > 0.1f) {
        const Vector3f& n = h.getNormal();
        const Vector3f& d = r.getDirection();
        Vector3f reflected = d - (2.0f * Vector3f::dot(n, d)) * n;
        Hit mirrorHit;
        color += ks * traceRay(Ray(p + 0.01f * reflected, reflected), 0, bounces - 1, mirrorHit);
    }
    color += _scene.getAmbientLight() * m->getDiffuseColor();
    return color;
}
