#include "ArgParser.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

[[noreturn]] void usage(const char* message)
{
    std::fprintf(stderr, "a2: %s\nusage: a2 -input scene.txt [-size w h] [-output a.png] "
                         "[-normals n.png] [-depth min max d.png] [-bounces n] [-shadows] "
                         "[-jitter] [-filter]\n", message);
    std::exit(2);
}

const char* value(int argc, char* argv[], int& i)
{
    if (i + 1 >= argc) usage((std::string("missing value after ") + argv[i]).c_str());
    return argv[++i];
}

int number(const char* s, const char* flag)
{
    char* end = nullptr;
    long v = std::strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < 0 || v > 100000) usage((std::string("bad number for ") + flag).c_str());
    return (int)v;
}

float real(const char* s, const char* flag)
{
    char* end = nullptr;
    float v = std::strtof(s, &end);
    if (*s == '\0' || *end != '\0') usage((std::string("bad number for ") + flag).c_str());
    return v;
}

}  // namespace

ArgParser::ArgParser(int argc, char* argv[])
{
    for (int i = 1; i < argc; ++i) {
        const char* a = argv[i];
        if (!std::strcmp(a, "-input")) {
            input_file = value(argc, argv, i);
        } else if (!std::strcmp(a, "-output")) {
            output_file = value(argc, argv, i);
        } else if (!std::strcmp(a, "-normals")) {
            normals_file = value(argc, argv, i);
        } else if (!std::strcmp(a, "-depth")) {
            depth_min = real(value(argc, argv, i), a);
            depth_max = real(value(argc, argv, i), a);
            depth_file = value(argc, argv, i);
        } else if (!std::strcmp(a, "-size")) {
            width = number(value(argc, argv, i), a);
            height = number(value(argc, argv, i), a);
        } else if (!std::strcmp(a, "-bounces")) {
            bounces = number(value(argc, argv, i), a);
        } else if (!std::strcmp(a, "-shadows")) {
            shadows = true;
        } else if (!std::strcmp(a, "-jitter")) {
            jitter = true;
        } else if (!std::strcmp(a, "-filter")) {
            filter = true;
        } else {
            usage((std::string("unknown option ") + a).c_str());
        }
    }
    if (input_file.empty()) usage("no -input scene");
    if (width < 1 || height < 1) usage("the size must be at least 1 x 1");
}
