#pragma once

// Private: shader programs and GL error checks shared by the renderers.

#include "gl.hpp"

namespace clutterscope::render::gl {

// Compiles and links a vertex + fragment program. Throws RenderError with `what` and the
// driver's log when either step fails.
Program link_program(const char* vertex_source, const char* fragment_source, const char* what);

// Throws RenderError naming `what` when GL has recorded an error.
void check_error(const char* what);

}  // namespace clutterscope::render::gl
