#include "programs/brdf_features.h"

#include <cctype>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace brdfa {

namespace {

bool identChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

}  // namespace

int countWholeWords(std::string_view text, std::string_view word) {
  int n = 0;
  for (size_t at = text.find(word); at != std::string_view::npos; at = text.find(word, at + 1)) {
    bool startOk = at == 0 || !identChar(text[at - 1]);
    bool endOk = at + word.size() >= text.size() || !identChar(text[at + word.size()]);
    if (startOk && endOk) ++n;
  }
  return n;
}

namespace {

// Names of the parameters of the first definition of `function` in `text`, e.g. BRDF(vec3 L,
// vec3 V, ...) -> {L, V, ...}. Empty when not found.
std::vector<std::string> parameterNames(std::string_view text, std::string_view function) {
  for (size_t at = text.find(function); at != std::string_view::npos; at = text.find(function, at + 1)) {
    if (at > 0 && identChar(text[at - 1])) continue;
    size_t open = at + function.size();
    while (open < text.size() && std::isspace(static_cast<unsigned char>(text[open]))) ++open;
    if (open >= text.size() || text[open] != '(') continue;
    size_t close = text.find(')', open);
    if (close == std::string_view::npos) return {};
    std::vector<std::string> names;
    std::string_view params = text.substr(open + 1, close - open - 1);
    size_t start = 0;
    while (start <= params.size()) {
      size_t comma = params.find(',', start);
      std::string_view p =
          params.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
      size_t end = p.size();
      while (end > 0 && !identChar(p[end - 1])) --end;
      size_t begin = end;
      while (begin > 0 && identChar(p[begin - 1])) --begin;
      names.emplace_back(p.substr(begin, end - begin));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    return names;
  }
  return {};
}

// `text` with each // and /* */ comment replaced by one space.
std::string withoutComments(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    if (text.compare(i, 2, "//") == 0) {
      i = text.find('\n', i);
      if (i == std::string_view::npos) break;
      out += ' ';
    } else if (text.compare(i, 2, "/*") == 0) {
      size_t end = text.find("*/", i + 2);
      i = end == std::string_view::npos ? text.size() : end + 2;
      out += ' ';
    } else {
      out += text[i++];
    }
  }
  return out;
}

}  // namespace

bool definesFunction(std::string_view code, std::string_view type, std::string_view name) {
  const std::string text = withoutComments(code);
  auto skipSpace = [&](size_t i) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    return i;
  };
  for (size_t at = text.find(type); at != std::string::npos; at = text.find(type, at + 1)) {
    if (at > 0 && identChar(text[at - 1])) continue;
    const size_t afterType = at + type.size();
    const size_t nameStart = skipSpace(afterType);
    if (nameStart == afterType) continue;  // "floatx" or "float(": not a declaration
    if (text.compare(nameStart, name.size(), name) != 0) continue;
    size_t i = nameStart + name.size();
    if (i < text.size() && identChar(text[i])) continue;
    i = skipSpace(i);
    if (i < text.size() && text[i] == '(') return true;
  }
  return false;
}

bool declaresName(std::string_view code, std::string_view name) {
  const std::string text = withoutComments(code);
  auto isSpace = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
    const size_t end = at + name.size();
    if ((at > 0 && identChar(text[at - 1])) || (end < text.size() && identChar(text[end]))) continue;
    const size_t newline = text.rfind('\n', at);
    const size_t first = text.find_first_not_of(" \t\r", newline == std::string::npos ? 0 : newline + 1);
    if (first < at && text[first] == '#') {
      // A directive: only `# define name` and `# undef name` give it a meaning here.
      std::string_view word(text.data() + first + 1, at - first - 1);
      while (!word.empty() && isSpace(word.front())) word.remove_prefix(1);
      while (!word.empty() && isSpace(word.back())) word.remove_suffix(1);
      if (word == "define" || word == "undef") return true;
      continue;
    }
    size_t before = at;
    while (before > 0 && std::isspace(static_cast<unsigned char>(text[before - 1]))) --before;
    if (before > 0 && text[before - 1] == ']') return true;
    if (before > 0 && identChar(text[before - 1])) {
      size_t wordStart = before;
      while (wordStart > 0 && identChar(text[wordStart - 1])) --wordStart;
      if (text.compare(wordStart, before - wordStart, "return") != 0) return true;
    }
    size_t after = end;
    while (after < text.size() && std::isspace(static_cast<unsigned char>(text[after]))) ++after;
    if (after < text.size() && text[after] == '=' && (after + 1 == text.size() || text[after + 1] != '=')) return true;
  }
  return false;
}

BrdfFeatures detectFeatures(const BrdfDefinition& brdf) {
  BrdfFeatures f;
  f.samplerPdf = brdf.hasSampler() && definesFunction(brdf.sampleShader, "float", "pdfBRDF");
  const std::string code = brdf.shader + "\n" + brdf.sampleShader;
  f.textures = false;
  for (const char* t : {"iTexture0", "iTexture1", "iTexture2", "iTexture3"})
    if (countWholeWords(code, t) > 0) f.textures = true;
  // `##` could paste the name together: counted as used.
  f.texCoord = brdf.format == BrdfFormat::Legacy || f.textures || countWholeWords(code, "texCoord") > 0 ||
               code.find("##") != std::string::npos;

  if (brdf.format == BrdfFormat::Legacy) {
    // render(L, N, V, textureCord, worldToLocal): the engine built worldToLocal from N and V
    // (kernels/shade.comp.glsl), never from the surface's tangent.
    f.tangentFrame = false;
    return f;
  }
  // name -> number of signatures declaring it. X, Y are parameters 4 and 5 of both
  // BRDF(L, V, N, X, Y) and sampleBRDF(u, V, N, X, Y, out L, out pdf).
  std::map<std::string, int> declared;
  for (const char* fn : {"BRDF", "sampleBRDF"}) {
    std::vector<std::string> names = parameterNames(code, fn);
    if (names.empty()) continue;
    if (names.size() < 5 || names[3].empty() || names[4].empty()) return f;  // unexpected: assume used
    ++declared[names[3]];
    ++declared[names[4]];
  }
  if (declared.empty()) return f;
  f.tangentFrame = false;
  for (const auto& [name, signatures] : declared)
    if (countWholeWords(code, name) > signatures) f.tangentFrame = true;  // read beyond its declarations
  return f;
}

}  // namespace brdfa
