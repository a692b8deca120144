// The BRDF file contract (docs/design.md section 3): Disney BRDF Explorer's .brdf text format.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/result.h"

namespace brdfa {

using Vec3 = std::array<float, 3>;

enum class ParamType { Float, Color, Bool };
const char* paramTypeName(ParamType type);

// One line of the `::begin parameters` section.
struct BrdfParam {
  std::string name;
  ParamType type = ParamType::Float;
  float min = 0.0f;  // Float only; Color is 0..1, Bool is 0|1
  float max = 1.0f;
  Vec3 defaultValue{0, 0, 0};  // Float and Bool use [0]
  int line = 0;                // 1-based line in the file
};

enum class BrdfFormat { Explorer, Legacy };

// What a file states about its BRDF, checked by Renderer::checkBrdf. Declared by a
// comment line outside the sections, which the Explorer's reader skips like any comment:
//   # claims: reciprocity, energy-conservation, non-negativity
// (names separated by commas or spaces; "none" claims nothing). A property not claimed is
// still measured and reported, never failed.
struct BrdfClaims {
  bool declared = false;            // the file has a claims line
  bool reciprocity = false;         // f(L, V) = f(V, L)
  bool energyConservation = false;  // directional albedo <= 1 at every view
  bool nonNegativity = false;       // every channel >= 0
  int line = 0;                     // of the claims line
};

// A parsed .brdf file. The GLSL sections are kept verbatim together with the file line on
// which they start, so diagnostics can be mapped back to the submitted text.
struct BrdfDefinition {
  BrdfFormat format = BrdfFormat::Explorer;
  std::vector<BrdfParam> params;
  std::string shader;        // body of `::begin shader` (defines vec3 BRDF(L, V, N, X, Y))
  int shaderFirstLine = 0;   // file line of the first line of `shader`
  std::string sampleShader;  // body of `::begin sample`, empty when absent
  int sampleFirstLine = 0;
  std::vector<Diagnostic> warnings;  // e.g. an ignored `isFunc` section
  BrdfClaims claims;
  // A measured BRDF (brdfa/measured.h): the registered measured asset whose table the program's
  // `measuredMERL()` reads (set 1, binding 6). Empty for every other file. Not part of the
  // program: every measured BRDF shares one compiled program and binds its own table.
  std::string measuredTable;

  const BrdfParam* findParam(std::string_view name) const;
  bool hasSampler() const { return !sampleShader.empty(); }
};

// Parses the text of a .brdf file. Never throws. A malformed parameter line yields a
// CompileError whose diagnostic carries that line. Checks that the shader section exists and
// that parameter names are GLSL identifiers, unique, and not reserved by the integrator.
Result<BrdfDefinition> parseBrdf(std::string_view text);

}  // namespace brdfa
