// What a BRDF's code reads, so programs compile in only what is used.
#pragma once

#include <string_view>

#include "brdfa/brdf.h"

namespace brdfa {

struct BrdfFeatures {
  bool tangentFrame = true;  // BRDF() (or sampleBRDF()) reads its X or Y argument (never for a
                             // legacy render(): the engine's worldToLocal is built from N and V)
  bool textures = true;      // the code names iTexture0..iTexture3
  bool texCoord = true;      // the code names texCoord (always for a legacy render(), which
                             // receives it), or a texture (which is looked up by it)
  bool samplerPdf = false;   // the sample section defines float pdfBRDF(...) (our extension)
};

// Conservative: anything it cannot prove unused counts as used. X and Y are the 4th and 5th
// parameters of BRDF()/sampleBRDF() under whatever names the file gives them; they count as
// unused when those names occur nowhere in the code except in the signatures. Textures count as
// unused when no iTextureN word occurs (a macro could still build the name; it then fails to
// compile with an undeclared identifier, never reads garbage).
// samplerPdf is set when the sample section, outside its // and /* */ comments, has
// `float pdfBRDF (` with whole words (a declaration without a body, or one inside an inactive
// #if, still counts: the check kernel then fails to compile, with the file's own line numbers).
BrdfFeatures detectFeatures(const BrdfDefinition& brdf);

// True when `code`, with its // and /* */ comments removed, contains `<type> <name> (` with
// `type` and `name` as whole words.
bool definesFunction(std::string_view code, std::string_view type, std::string_view name);

// Occurrences of `word` in `text` not inside a longer identifier.
int countWholeWords(std::string_view text, std::string_view word);

// True when `code`, outside its // and /* */ comments, gives `name` a meaning of its own: a
// `#define name` or `#undef name` line, a declaration (`name` right after a type or qualifier
// word other than `return`, or after `]`: `const float name = ...`, `float name(`, a parameter
// or struct member), or a store into it (`name =`). Uses in expressions (`2.0 * name`,
// `return name;`, `f(name)`) are not.
bool declaresName(std::string_view code, std::string_view name);

}  // namespace brdfa
