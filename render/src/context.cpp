#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <clutterscope/render/context.hpp>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "gl.hpp"

namespace clutterscope::render {

namespace {

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default: {
      std::ostringstream text;
      text << "EGL error 0x" << std::hex << code;
      return text.str();
    }
  }
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t length = std::strlen(name);
  for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + 1, name)) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[length] == '\0' || p[length] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

template <typename Function>
Function egl_function(const char* name) {
  return reinterpret_cast<Function>(eglGetProcAddress(name));
}

// An initialised EGL display shared by every context of the process. EGL displays are
// per-device singletons and eglTerminate would destroy every other thread's context, so
// displays are reference-counted here and terminated only when the last context is gone.
struct SharedDisplay {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string description;  // which platform/device was used, for error messages
  int references = 0;
};

std::mutex& display_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::map<int, SharedDisplay>& displays() {  // keyed by requested device index (-1 = auto)
  static std::map<int, SharedDisplay> map;
  return map;
}

struct DeviceChoice {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string description;
};

// Device platform first (a hardware device preferred over EGL_MESA_device_software), then
// the surfaceless Mesa platform. Returns an initialised display or throws RenderError.
DeviceChoice open_display(int device_index) {
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::string failures;
  auto get_platform_display =
      egl_function<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");

  auto try_initialise = [&](EGLDisplay display, const std::string& description) -> bool {
    if (display == EGL_NO_DISPLAY) {
      failures += "\n  " + description + ": no display (" + egl_error_name(eglGetError()) + ")";
      return false;
    }
    EGLint major = 0, minor = 0;
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
      failures +=
          "\n  " + description + ": eglInitialize failed (" + egl_error_name(eglGetError()) + ")";
      return false;
    }
    return true;
  };

  if (get_platform_display != nullptr &&
      has_extension(client_extensions, "EGL_EXT_platform_device")) {
    auto query_devices = egl_function<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
    auto query_device_string =
        egl_function<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
    EGLint count = 0;
    if (query_devices != nullptr && query_devices(0, nullptr, &count) == EGL_TRUE && count > 0) {
      std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
      query_devices(count, devices.data(), &count);
      devices.resize(static_cast<std::size_t>(count));
      if (device_index >= count) {
        throw RenderError("EGL device index " + std::to_string(device_index) +
                          " requested, but only " + std::to_string(count) + " devices exist");
      }
      // Candidate order: the requested device, else hardware devices before software ones.
      std::vector<int> order;
      if (device_index >= 0) {
        order.push_back(device_index);
      } else {
        for (int pass = 0; pass < 2; ++pass) {
          for (int i = 0; i < count; ++i) {
            const char* extensions = query_device_string != nullptr
                                         ? query_device_string(devices[i], EGL_EXTENSIONS)
                                         : nullptr;
            const bool software = has_extension(extensions, "EGL_MESA_device_software");
            if (software == (pass == 1)) order.push_back(i);
          }
        }
      }
      for (const int i : order) {
        const std::string description = "EGL device " + std::to_string(i);
        EGLDisplay display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (try_initialise(display, description)) return {display, description};
      }
    } else {
      failures += "\n  EGL_EXT_device_enumeration: no devices";
    }
  } else {
    failures += "\n  EGL_EXT_platform_device: not supported by this EGL";
  }

  if (device_index < 0 && get_platform_display != nullptr &&
      has_extension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay display =
        get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (try_initialise(display, "surfaceless Mesa platform")) {
      return {display, "surfaceless Mesa platform"};
    }
  }
  throw RenderError(
      "no usable EGL display (install libegl1 libegl-mesa0 libgl1-mesa-dri for the software "
      "renderer, or a GPU driver with EGL):" +
      failures);
}

EGLDisplay acquire_display(int device_index) {
  std::lock_guard<std::mutex> lock(display_mutex());
  SharedDisplay& shared = displays()[device_index];
  if (shared.references == 0) {
    DeviceChoice choice = open_display(device_index);
    shared.display = choice.display;
    shared.description = choice.description;
  }
  ++shared.references;
  return shared.display;
}

void release_display(int device_index) {
  std::lock_guard<std::mutex> lock(display_mutex());
  SharedDisplay& shared = displays()[device_index];
  if (--shared.references == 0) {
    eglTerminate(shared.display);
    shared.display = EGL_NO_DISPLAY;
  }
}

std::string gl_string(GLenum name) {
  const GLubyte* text = glGetString(name);
  return text != nullptr ? reinterpret_cast<const char*>(text) : "";
}

}  // namespace

struct EglContext::State {
  int device_index = -1;
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  std::string renderer;
  std::string version;
};

EglContext::EglContext(std::unique_ptr<State> state) : state_(std::move(state)) {}
EglContext::EglContext(EglContext&&) noexcept = default;
EglContext& EglContext::operator=(EglContext&& other) noexcept {
  if (this != &other) {
    EglContext discarded(std::move(*this));
    state_ = std::move(other.state_);
  }
  return *this;
}

EglContext::~EglContext() {
  if (!state_) return;
  if (eglGetCurrentContext() == state_->context) {
    eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  eglDestroyContext(state_->display, state_->context);
  eglReleaseThread();
  release_display(state_->device_index);
}

EglContext EglContext::create(const EglOptions& options) {
  if (options.device_index < -1) {
    throw RenderError("EglOptions::device_index must be >= -1, got " +
                      std::to_string(options.device_index));
  }
  auto state = std::make_unique<State>();
  state->device_index = options.device_index;
  state->display = acquire_display(options.device_index);
  struct DisplayGuard {  // gives the display reference back if creation fails below
    State* state;
    ~DisplayGuard() {
      if (state != nullptr) release_display(state->device_index);
    }
  } guard{state.get()};

  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {  // per thread
    throw RenderError("eglBindAPI(EGL_OPENGL_API) failed: " + egl_error_name(eglGetError()));
  }
  const char* display_extensions = eglQueryString(state->display, EGL_EXTENSIONS);
  if (!has_extension(display_extensions, "EGL_KHR_surfaceless_context")) {
    throw RenderError("EGL display lacks EGL_KHR_surfaceless_context");
  }

  EGLConfig config = nullptr;
  EGLint config_count = 0;
  for (const EGLint surface_type : {EGLint{EGL_PBUFFER_BIT}, EGLint{EGL_DONT_CARE}}) {
    const EGLint attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                 surface_type, EGL_NONE};
    if (eglChooseConfig(state->display, attributes, &config, 1, &config_count) == EGL_TRUE &&
        config_count > 0) {
      break;
    }
  }
  if (config_count == 0) {
    if (!has_extension(display_extensions, "EGL_KHR_no_config_context")) {
      throw RenderError("no EGL config with desktop OpenGL support");
    }
    config = EGL_NO_CONFIG_KHR;
  }

  // Desktop GL core, newest first (llvmpipe refuses 4.6).
  const std::pair<int, int> versions[] = {{4, 6}, {4, 5}, {4, 3}, {3, 3}};
  std::string tried;
  for (const auto& [major, minor] : versions) {
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 major,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 minor,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    state->context = eglCreateContext(state->display, config, EGL_NO_CONTEXT, attributes);
    if (state->context != EGL_NO_CONTEXT) break;
    tried += " " + std::to_string(major) + "." + std::to_string(minor) + " (" +
             egl_error_name(eglGetError()) + ")";
  }
  if (state->context == EGL_NO_CONTEXT) {
    throw RenderError("cannot create a desktop OpenGL core context; tried" + tried);
  }
  if (eglMakeCurrent(state->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state->context) != EGL_TRUE) {
    const std::string error = egl_error_name(eglGetError());
    eglDestroyContext(state->display, state->context);
    throw RenderError("eglMakeCurrent failed: " + error);
  }
  state->renderer = gl_string(GL_RENDERER);
  state->version = gl_string(GL_VERSION);
  guard.state = nullptr;
  return EglContext(std::move(state));
}

void EglContext::make_current() const {
  if (!state_) throw RenderError("make_current on a moved-from EglContext");
  eglBindAPI(EGL_OPENGL_API);
  if (eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state_->context) !=
      EGL_TRUE) {
    throw RenderError("eglMakeCurrent failed: " + egl_error_name(eglGetError()));
  }
}

std::string EglContext::renderer() const { return state_ ? state_->renderer : ""; }
std::string EglContext::version() const { return state_ ? state_->version : ""; }

bool EglContext::is_software() const {
  const std::string& name = renderer();
  for (const char* software : {"llvmpipe", "softpipe", "swrast", "SWR", "lavapipe"}) {
    if (name.find(software) != std::string::npos) return true;
  }
  return false;
}

bool egl_available(std::string* why_not) {
  try {
    acquire_display(-1);
    release_display(-1);
    return true;
  } catch (const RenderError& error) {
    if (why_not != nullptr) *why_not = error.what();
    return false;
  }
}

}  // namespace clutterscope::render
