// The GLSL text of shaders/lib and shaders/kernels, read once at start-up.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "brdfa/result.h"
#include "programs/program_assembler.h"

namespace brdfa {

class ShaderSources {
 public:
  // Reads every file in <dir>/lib, <dir>/lib/terms and <dir>/kernels; NotFound when lib or
  // kernels is missing (lib/terms may be). Also makes the terms the default of assembleProgram (setDefaultTermSources).
  static Result<ShaderSources> load(const std::string& shaderDir);

  // Text of "lib/<name>" or "kernels/<name>"; empty when absent (callers check at start-up).
  const std::string& get(const std::string& relativePath) const;

  // The shared terms of lib/terms, keyed "terms/<name>.glsl" (for ProgramSpec::terms).
  const TermSources& terms() const { return terms_; }

  // "#version 450", `#extension X : require` for each of `extensions`, `#define` for each of
  // `defines`, then the named pieces in order: a fixed kernel with no BRDF.
  std::string assembleFixed(const std::vector<std::string>& defines, const std::vector<std::string>& pieces,
                            const std::vector<std::string>& extensions = {}) const;

 private:
  std::map<std::string, std::string> files_;
  TermSources terms_;
};

}  // namespace brdfa
