// What a BRDF's code reads, so programs compile in only what is used.
#pragma once

#include "brdfa/brdf.h"

namespace brdfa {

struct BrdfFeatures {
  bool tangentFrame = true;  // BRDF() (or sampleBRDF()) reads its X or Y argument
};

// Conservative: anything it cannot prove unused counts as used. X and Y are the 4th and 5th
// parameters of BRDF()/sampleBRDF() under whatever names the file gives them; they count as
// unused when those names occur nowhere in the code except in the signatures.
BrdfFeatures detectFeatures(const BrdfDefinition& brdf);

}  // namespace brdfa
