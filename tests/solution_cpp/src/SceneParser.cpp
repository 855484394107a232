#include "SceneParser.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace {

float radians(float degrees)
{
    return (float)(M_PI * (double)degrees / 180.0);
}

}  // namespace

SceneParser::SceneParser(const std::string& name) : filename(name)
{
    size_t slash = name.find_last_of('/');
    directory = slash == std::string::npos ? "." : name.substr(0, slash);
    std::ifstream f(name);
    if (!f) {
        std::fprintf(stderr, "%s: cannot open the scene file\n", name.c_str());
        std::exit(2);
    }
    std::string line;
    int lineno = 0;
    while (std::getline(f, line)) {
        ++lineno;
        std::istringstream ss(line);
        std::string word;
        while (ss >> word) tokens.push_back(Token{word, lineno});
    }
    while (pos < tokens.size()) {
        const Token& block = next("a block");
        if (block.text == "PerspectiveCamera") {
            parsePerspectiveCamera();
        } else if (block.text == "Background") {
            parseBackground();
        } else if (block.text == "Lights") {
            parseLights();
        } else if (block.text == "Materials") {
            parseMaterials();
        } else if (block.text == "Group") {
            delete group;
            group = parseGroup();
        } else {
            fail("unknown block '" + block.text + "'", block.line);
        }
    }
    if (!camera) fail("no PerspectiveCamera block", lineno);
    if (!group) group = new Group();
    // a scene without lights is lit by a white ambient light
    if (lights.empty()) ambient_light = Vector3f(1, 1, 1);
}

SceneParser::~SceneParser()
{
    delete group;
    delete camera;
    for (Light* l : lights) delete l;
    for (Material* m : materials) delete m;
}

Vector3f SceneParser::getBackgroundColor(const Vector3f& dir) const
{
    return cubemap ? (*cubemap)(dir) : background_color;
}

void SceneParser::fail(const std::string& message, int line) const
{
    std::fprintf(stderr, "%s:%d: %s\n", filename.c_str(), line, message.c_str());
    std::exit(2);
}

const SceneParser::Token& SceneParser::next(const char* what)
{
    if (pos >= tokens.size()) {
        fail(std::string("expected ") + what + ", found the end of the file",
             tokens.empty() ? 1 : tokens.back().line);
    }
    return tokens[pos++];
}

bool SceneParser::peekIs(const char* text) const
{
    return pos < tokens.size() && tokens[pos].text == text;
}

void SceneParser::expect(const char* text)
{
    const Token& t = next(text);
    if (t.text != text) fail(std::string("expected '") + text + "', found '" + t.text + "'", t.line);
}

// a number as C's %f reads it: one closing brace glued to its end is the next token
float SceneParser::readFloat(const char* what)
{
    Token t = next(what);
    const char* s = t.text.c_str();
    char* end = nullptr;
    float value = std::strtof(s, &end);
    std::string rest(end);
    if (end == s || (!rest.empty() && rest != "}") || std::isalpha((unsigned char)s[0])) {
        fail(std::string("expected a number for ") + what + ", found '" + t.text + "'", t.line);
    }
    if (rest == "}") tokens[--pos] = Token{"}", t.line};
    return value;
}

int SceneParser::readInt(const char* what)
{
    Token t = next(what);
    char* end = nullptr;
    long value = std::strtol(t.text.c_str(), &end, 10);
    std::string rest(end);
    if (end == t.text.c_str() || (!rest.empty() && rest != "}") || value < 0 || value > 1000000) {
        fail(std::string("expected a count or index for ") + what + ", found '" + t.text + "'", t.line);
    }
    if (rest == "}") tokens[--pos] = Token{"}", t.line};
    return (int)value;
}

Vector3f SceneParser::readVector3f(const char* what)
{
    float x = readFloat(what);
    float y = readFloat(what);
    float z = readFloat(what);
    return Vector3f(x, y, z);
}

std::string SceneParser::resolve(const std::string& path) const
{
    return !path.empty() && path[0] == '/' ? path : directory + "/" + path;
}

void SceneParser::parsePerspectiveCamera()
{
    expect("{");
    expect("center");
    Vector3f center = readVector3f("center");
    expect("direction");
    Vector3f direction = readVector3f("direction");
    expect("up");
    Vector3f up = readVector3f("up");
    expect("angle");
    float angle = radians(readFloat("angle"));
    expect("}");
    delete camera;
    camera = new PerspectiveCamera(center, direction, up, angle);
}

void SceneParser::parseBackground()
{
    expect("{");
    for (;;) {
        const Token& t = next("a Background field");
        if (t.text == "}") break;
        if (t.text == "color") {
            background_color = readVector3f("color");
        } else if (t.text == "ambientLight") {
            ambient_light = readVector3f("ambientLight");
        } else if (t.text == "cubeMap") {
            cubemap.reset(new CubeMap(resolve(next("a cube map folder").text)));
        } else {
            fail("unknown Background field '" + t.text + "'", t.line);
        }
    }
}

void SceneParser::parseLights()
{
    for (Light* l : lights) delete l;
    lights.clear();
    expect("{");
    expect("numLights");
    int n = readInt("numLights");
    for (int i = 0; i < n; ++i) {
        const Token& t = next("a light");
        if (t.text == "DirectionalLight") {
            lights.push_back(parseDirectionalLight());
        } else if (t.text == "PointLight") {
            lights.push_back(parsePointLight());
        } else {
            fail("unknown light '" + t.text + "'", t.line);
        }
    }
    expect("}");
}

Light* SceneParser::parseDirectionalLight()
{
    expect("{");
    expect("direction");
    Vector3f direction = readVector3f("direction").normalized();
    expect("color");
    Vector3f color = readVector3f("color");
    expect("}");
    return new DirectionalLight(direction, color);
}

Light* SceneParser::parsePointLight()
{
    Vector3f position(0, 0, 0), color(0, 0, 0);
    float falloff = 0;
    expect("{");
    for (;;) {
        const Token& t = next("a PointLight field");
        if (t.text == "}") break;
        if (t.text == "position") {
            position = readVector3f("position");
        } else if (t.text == "color") {
            color = readVector3f("color");
        } else if (t.text == "falloff") {
            falloff = readFloat("falloff");
        } else {
            fail("unknown PointLight field '" + t.text + "'", t.line);
        }
    }
    return new PointLight(position, color, falloff);
}

void SceneParser::parseMaterials()
{
    for (Material* m : materials) delete m;
    materials.clear();
    expect("{");
    expect("numMaterials");
    int n = readInt("numMaterials");
    for (int i = 0; i < n; ++i) {
        const Token& t = next("a material");
        if (t.text != "Material" && t.text != "PhongMaterial") {
            fail("expected Material or PhongMaterial, found '" + t.text + "'", t.line);
        }
        materials.push_back(parseMaterial());
    }
    expect("}");
}

Material* SceneParser::parseMaterial()
{
    Vector3f diffuse(1, 1, 1), specular(0, 0, 0);
    float shininess = 0;
    expect("{");
    for (;;) {
        const Token& t = next("a Material field");
        if (t.text == "}") break;
        if (t.text == "diffuseColor") {
            diffuse = readVector3f("diffuseColor");
        } else if (t.text == "specularColor") {
            specular = readVector3f("specularColor");
        } else if (t.text == "shininess") {
            shininess = readFloat("shininess");
        } else if (t.text == "bump") {
            next("a bump map name");  // not used
        } else {
            fail("unknown Material field '" + t.text + "'", t.line);
        }
    }
    return new Material(diffuse, specular, shininess);
}

Object3D* SceneParser::parseObject(const Token& kind)
{
    if (kind.text == "Group") return parseGroup();
    if (kind.text == "Transform") return parseTransform();
    if (!current_material) fail("an object before any MaterialIndex", kind.line);
    if (kind.text == "Sphere") {
        expect("{");
        expect("center");
        Vector3f center = readVector3f("center");
        expect("radius");
        float radius = readFloat("radius");
        expect("}");
        return new Sphere(center, radius, current_material);
    }
    if (kind.text == "Plane") {
        expect("{");
        expect("normal");
        Vector3f normal = readVector3f("normal");
        expect("offset");
        float offset = readFloat("offset");
        expect("}");
        return new Plane(normal, offset, current_material);
    }
    if (kind.text == "Triangle") return parseTriangle();
    if (kind.text == "TriangleMesh") {
        expect("{");
        expect("obj_file");
        std::string path = resolve(next("an OBJ file name").text);
        expect("}");
        return new Mesh(path, current_material);
    }
    fail("unknown object '" + kind.text + "'", kind.line);
}

Group* SceneParser::parseGroup()
{
    expect("{");
    expect("numObjects");
    int n = readInt("numObjects");
    Group* g = new Group();
    int count = 0;
    for (;;) {
        const Token& t = next("an object or '}'");
        if (t.text == "}") break;
        if (t.text == "MaterialIndex") {
            int line = t.line;
            int index = readInt("MaterialIndex");
            if (index >= (int)materials.size()) fail("MaterialIndex out of range", line);
            current_material = materials[index];
            continue;
        }
        g->addObject(parseObject(t));
        ++count;
    }
    if (count != n) fail("numObjects does not match the objects in the Group", tokens[pos - 1].line);
    return g;
}

Object3D* SceneParser::parseTriangle()
{
    expect("{");
    expect("vertex0");
    Vector3f a = readVector3f("vertex0");
    expect("vertex1");
    Vector3f b = readVector3f("vertex1");
    expect("vertex2");
    Vector3f c = readVector3f("vertex2");
    expect("}");
    Triangle* t = new Triangle(a, b, c, current_material);
    Vector3f n = Vector3f::cross(b - a, c - a).normalized();
    for (int k = 0; k < 3; ++k) t->normals[k] = n;
    return t;
}

Object3D* SceneParser::parseTransform()
{
    expect("{");
    Matrix4f m = Matrix4f::identity();
    for (;;) {
        const Token& t = next("a transform op or an object");
        if (t.text == "Translate") {
            Vector3f v = readVector3f("Translate");
            m = m * Matrix4f::translation(v[0], v[1], v[2]);
        } else if (t.text == "Scale") {
            Vector3f v = readVector3f("Scale");
            m = m * Matrix4f::scaling(v[0], v[1], v[2]);
        } else if (t.text == "UniformScale") {
            m = m * Matrix4f::uniformScaling(readFloat("UniformScale"));
        } else if (t.text == "XRotate") {
            m = m * Matrix4f::rotateX(radians(readFloat("XRotate")));
        } else if (t.text == "YRotate") {
            m = m * Matrix4f::rotateY(radians(readFloat("YRotate")));
        } else if (t.text == "ZRotate") {
            m = m * Matrix4f::rotateZ(radians(readFloat("ZRotate")));
        } else if (t.text == "Rotate") {
            expect("{");
            Vector3f axis = readVector3f("Rotate");
            float angle = radians(readFloat("Rotate"));
            expect("}");
            m = m * Matrix4f::rotation(axis, angle);
        } else if (t.text == "Matrix4f") {
            // sixteen numbers, column by column; it multiplies from the left
            expect("{");
            Matrix4f file;
            for (int j = 0; j < 4; ++j)
                for (int i = 0; i < 4; ++i) file(i, j) = readFloat("Matrix4f");
            expect("}");
            m = file * m;
        } else {
            Object3D* child = parseObject(t);
            expect("}");
            return new Transform(m, child);
        }
    }
}
