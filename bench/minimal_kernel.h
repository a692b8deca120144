// The reference kernel for throughput (see minimal_kernel.glsl), driven with raw Vulkan.
#pragma once

#include <memory>
#include <string>

#include "brdfa/result.h"

namespace brdfa::bench {

class MinimalKernel {
 public:
  // Compiles the kernel and uploads the sky; its own Vulkan device, like a separate program.
  static Result<std::unique_ptr<MinimalKernel>> create(const std::string& sourceDir, int width, int height);
  ~MinimalKernel();

  // One dispatch of `samples` samples per pixel; returns wall milliseconds (submit to fence).
  Result<double> pass(int samples);

 private:
  struct State;
  explicit MinimalKernel(std::unique_ptr<State> s);
  std::unique_ptr<State> s_;
};

// Pixels covered by the unit sphere seen from (0,0,3) with a 45 degree vertical field of view.
int spherePixels(int width, int height);

}  // namespace brdfa::bench
