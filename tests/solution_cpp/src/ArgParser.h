#ifndef ARG_PARSER_H
#define ARG_PARSER_H

#include <string>

// The course's command line: -input scene.txt -size w h -output a.png -normals n.png
// -depth min max d.png -bounces n -shadows -jitter -filter
class ArgParser {
public:
    ArgParser(int argc, char* argv[]);

    std::string input_file;
    std::string output_file;
    std::string normals_file;
    std::string depth_file;
    float depth_min = 0;
    float depth_max = 1;
    int width = 100;
    int height = 100;
    int bounces = 0;
    bool shadows = false;
    bool jitter = false;
    bool filter = false;
};

#endif
