#include "programs/shader_sources.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

namespace brdfa {

Result<ShaderSources> ShaderSources::load(const std::string& shaderDir) {
  namespace fs = std::filesystem;
  ShaderSources sources;
  for (const char* sub : {"lib", "kernels", "lib/terms"}) {
    fs::path dir = fs::path(shaderDir) / sub;
    std::error_code ec;
    // lib/terms is optional, so an older shader tree (a bench's A/B side) still loads.
    if (!fs::is_directory(dir, ec) && std::string_view(sub) == "lib/terms") continue;
    if (!fs::is_directory(dir, ec)) return makeError(ErrorCode::NotFound, "shader folder not found: " + dir.string());
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (!entry.is_regular_file()) continue;
      std::ifstream in(entry.path(), std::ios::binary);
      std::stringstream text;
      text << in.rdbuf();
      sources.files_[std::string(sub) + "/" + entry.path().filename().string()] = text.str();
    }
  }
  // The shared terms BRDF files include, keyed as they name them ("terms/<name>.glsl").
  for (const auto& [path, text] : sources.files_)
    if (path.starts_with("lib/terms/")) sources.terms_[path.substr(4)] = text;
  setDefaultTermSources(sources.terms_);
  return sources;
}

const std::string& ShaderSources::get(const std::string& relativePath) const {
  static const std::string empty;
  auto it = files_.find(relativePath);
  return it == files_.end() ? empty : it->second;
}

std::string ShaderSources::assembleFixed(const std::vector<std::string>& defines,
                                         const std::vector<std::string>& pieces,
                                         const std::vector<std::string>& extensions) const {
  std::string out = "#version 450\n";
  for (const auto& e : extensions) out += "#extension " + e + " : require\n";
  for (const auto& d : defines) out += "#define " + d + "\n";
  for (const auto& p : pieces) {
    out += "#line 1 0\n";
    out += get(p);
    out += "\n";
  }
  return out;
}

}  // namespace brdfa
