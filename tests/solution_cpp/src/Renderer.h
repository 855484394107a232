#ifndef RENDERER_H
#define RENDERER_H

#include "ArgParser.h"
#include "Hit.h"
#include "Ray.h"
#include "SceneParser.h"
#include "vecmath.h"

class Renderer {
public:
    explicit Renderer(const ArgParser& args);
    // renders the scene and writes the images the command line names
    void Render();
private:
    // the color seen along r; h receives the closest hit (t = FLT_MAX where nothing is hit)
    Vector3f traceRay(const Ray& r, float tmin, int bounces, Hit& h) const;

    ArgParser _args;
    SceneParser _scene;
};

#endif
