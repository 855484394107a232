#ifndef SCENE_PARSER_H
#define SCENE_PARSER_H

#include <memory>
#include <string>
#include <vector>

#include "Camera.h"
#include "CubeMap.h"
#include "Light.h"
#include "Material.h"
#include "Mesh.h"
#include "Object3D.h"
#include "vecmath.h"

// Reads a scene in the course's format (docs/course-format.md of raycheck). A scene it cannot
// read is reported on stderr with the file and line, and the program exits with status 2.
class SceneParser {
public:
    explicit SceneParser(const std::string& filename);
    ~SceneParser();

    Camera* getCamera() const { return camera; }
    Vector3f getBackgroundColor(const Vector3f& dir) const;
    const Vector3f& getAmbientLight() const { return ambient_light; }
    int getNumLights() const { return (int)lights.size(); }
    Light* getLight(int i) const { return lights[i]; }
    int getNumMaterials() const { return (int)materials.size(); }
    Material* getMaterial(int i) const { return materials[i]; }
    Group* getGroup() const { return group; }

private:
    struct Token {
        std::string text;
        int line;
    };
    [[noreturn]] void fail(const std::string& message, int line) const;
    const Token& next(const char* what);
    bool peekIs(const char* text) const;
    void expect(const char* text);
    float readFloat(const char* what);
    int readInt(const char* what);
    Vector3f readVector3f(const char* what);
    std::string resolve(const std::string& path) const;

    void parsePerspectiveCamera();
    void parseBackground();
    void parseLights();
    Light* parseDirectionalLight();
    Light* parsePointLight();
    void parseMaterials();
    Material* parseMaterial();
    Object3D* parseObject(const Token& kind);
    Group* parseGroup();
    Object3D* parseTriangle();
    Object3D* parseTransform();

    std::string filename, directory;
    std::vector<Token> tokens;
    size_t pos = 0;

    Camera* camera = nullptr;
    Vector3f background_color = Vector3f(0.5f, 0.5f, 0.5f);
    Vector3f ambient_light = Vector3f(0, 0, 0);
    std::unique_ptr<CubeMap> cubemap;
    std::vector<Light*> lights;
    std::vector<Material*> materials;
    Material* current_material = nullptr;
    Group* group = nullptr;
};

#endif
