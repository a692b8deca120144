// The GLSL text of shaders/lib and shaders/kernels, read once at start-up.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "brdfa/result.h"

namespace brdfa {

class ShaderSources {
 public:
  // Reads every file in <dir>/lib and <dir>/kernels; NotFound when the folder is missing.
  static Result<ShaderSources> load(const std::string& shaderDir);

  // Text of "lib/<name>" or "kernels/<name>"; empty when absent (callers check at start-up).
  const std::string& get(const std::string& relativePath) const;

  // "#version 450", `#extension X : require` for each of `extensions`, `#define` for each of
  // `defines`, then the named pieces in order: a fixed kernel with no BRDF.
  std::string assembleFixed(const std::vector<std::string>& defines, const std::vector<std::string>& pieces,
                            const std::vector<std::string>& extensions = {}) const;

 private:
  std::map<std::string, std::string> files_;
};

}  // namespace brdfa
