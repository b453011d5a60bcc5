// The one place the OpenGL 4.5 core API is included (glvnd's libOpenGL exports every entry point).
#pragma once

#include <GL/glcorearb.h>
