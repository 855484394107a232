#include "ArgParser.h"
#include "Renderer.h"

int main(int argc, char* argv[])
{
    ArgParser args(argc, argv);
    Renderer renderer(args);
    renderer.Render();
    return 0;
}
