#pragma once

// Which rasteriser made a result: every rendering command records it in run.json
// ("gl_renderer") and prints it on stderr unless -q (results differ between llvmpipe and GPU
// drivers). A header of its own, so that the commands need not include the EGL context's.

#include <string>

namespace clutterscope::render {

// "GL_RENDERER (GL_VERSION)" of the first context this process created (EglContext::create),
// "" while none was. Thread-safe.
std::string renderer_in_use();

}  // namespace clutterscope::render
