#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cstdlib>
#include <optional>
#include <string>

#include "requirements.hpp"

namespace clutterscope::render {
namespace {

class ContextGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
};

bool on_software_device(const EglContext& context) {
  return context.is_software() && context.display_description().rfind("EGL device ", 0) == 0;
}

// Contexts on one llvmpipe screen rasterise one at a time, so concurrent software contexts go
// to the device display and the surfaceless one alternately (whichever holds fewer).
TEST_F(ContextGl, ConcurrentSoftwareContextsAlternateBetweenTwoScreens) {
  std::optional<EglContext> first(EglContext::create());
  std::optional<EglContext> second(EglContext::create());
  const EglContext third = EglContext::create();
  if (!on_software_device(*first)) {
    // A hardware device (or only the surfaceless platform): every context shares it.
    EXPECT_EQ(second->display_description(), first->display_description());
    EXPECT_EQ(third.display_description(), first->display_description());
    return;
  }
  EXPECT_EQ(second->display_description(), "surfaceless Mesa platform (second software screen)");
  EXPECT_TRUE(second->is_software());
  EXPECT_EQ(second->renderer(), first->renderer());
  EXPECT_EQ(third.display_description(), first->display_description());
  // The second screen's only context gone, the next context takes its place.
  second.reset();
  const EglContext fourth = EglContext::create();
  EXPECT_EQ(fourth.display_description(), "surfaceless Mesa platform (second software screen)");
  first.reset();
  const EglContext fifth = EglContext::create();
  EXPECT_TRUE(on_software_device(fifth)) << fifth.display_description();
}

// Sets an environment variable for a scope and restores its previous value.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const char* value) : name_(name) {
    if (const char* previous = std::getenv(name)) previous_ = previous;
    ::setenv(name, value, 1);
  }
  ~ScopedEnvironment() {
    if (previous_) {
      ::setenv(name_, previous_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
  std::optional<std::string> previous_;
};

// CLUTTERSCOPE_EGL_DEVICE picks the device when the options leave the choice automatic; a
// value that is no device index is refused, naming the variable.
TEST_F(ContextGl, EglDeviceVariableSelectsTheDeviceAndIsValidated) {
  for (const char* bad : {"x", "-1", "1.5", " 0", "0x1", "99999999999"}) {
    const ScopedEnvironment variable("CLUTTERSCOPE_EGL_DEVICE", bad);
    try {
      EglContext::create();
      ADD_FAILURE() << "accepted CLUTTERSCOPE_EGL_DEVICE=" << bad;
    } catch (const RenderError& error) {
      EXPECT_NE(std::string(error.what()).find("CLUTTERSCOPE_EGL_DEVICE"), std::string::npos)
          << error.what();
    }
  }
  {
    const ScopedEnvironment variable("CLUTTERSCOPE_EGL_DEVICE", "99999");
    EXPECT_THROW(EglContext::create(), RenderError);  // no such device
  }
  std::optional<EglContext> device0;
  try {
    device0.emplace(EglContext::create(EglOptions{0}));
  } catch (const RenderError& error) {
    CLUTTERSCOPE_SKIP_OR_FAIL("EGL")
        << "no EGL device 0 (surfaceless platform only): " << error.what();
  }
  ASSERT_EQ(device0->display_description(), "EGL device 0");
  {
    const ScopedEnvironment variable("CLUTTERSCOPE_EGL_DEVICE", "99999");
    EXPECT_EQ(EglContext::create(EglOptions{0}).display_description(), "EGL device 0")
        << "an index in the options comes before the variable";
  }
  const ScopedEnvironment variable("CLUTTERSCOPE_EGL_DEVICE", "0");
  EXPECT_EQ(EglContext::create().display_description(), "EGL device 0");
}

// Displays are terminated with their last context and initialised again for the next one.
TEST_F(ContextGl, ContextsWorkAfterEveryDisplayWasTerminated) {
  for (int round = 0; round < 2; ++round) {
    const EglContext a = EglContext::create();
    const EglContext b = EglContext::create();
    for (const EglContext* context : {&a, &b}) {
      context->make_current();
      Renderer renderer(*context);
      const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.1f, 0.1f, 0.1f), 1));
      Intrinsics k;
      k.fx = k.fy = 500;
      k.cx = 32;
      k.cy = 24;
      k.width = 64;
      k.height = 48;
      Instance instance;
      instance.mesh = &box;
      instance.model_to_camera.translation() = Eigen::Vector3d(0, 0, 1);
      const DepthLabelImage image = renderer.render(k, {instance});
      EXPECT_FLOAT_EQ(image.depth.at<float>(24, 32), 0.95f) << context->display_description();
    }
  }
}

}  // namespace
}  // namespace clutterscope::render
