#include "programs/spirv_resources.h"

#include <map>
#include <optional>

namespace brdfa {
namespace {

// SPIR-V 1.3 opcodes, decorations and storage classes (the SPIR-V specification, section 3).
constexpr uint32_t kOpName = 5, kOpTypePointer = 32, kOpVariable = 59, kOpDecorate = 71, kOpControlBarrier = 224,
                   kOpMemoryBarrier = 225;
constexpr uint32_t kDecorationBuiltIn = 11, kDecorationBinding = 33, kDecorationDescriptorSet = 34;
constexpr uint32_t kUniformConstant = 0, kInput = 1, kUniform = 2, kOutput = 3, kWorkgroup = 4, kCrossWorkgroup = 5,
                   kImage = 11, kStorageBuffer = 12;

std::string literalString(const std::vector<uint32_t>& words, size_t from, size_t end) {
  std::string s;
  for (size_t i = from; i < end; ++i)
    for (int b = 0; b < 4; ++b) {
      const char c = static_cast<char>((words[i] >> (8 * b)) & 0xFF);
      if (c == '\0') return s;
      s.push_back(c);
    }
  return s;
}

}  // namespace

std::vector<ForeignResource> foreignResources(const std::vector<uint32_t>& words,
                                              const std::set<DescriptorSlot>& layout,
                                              const std::set<std::string>& aliases) {
  std::map<uint32_t, std::string> names;
  std::map<uint32_t, uint32_t> pointee;  // pointer type -> pointed-to type
  std::map<uint32_t, uint32_t> sets, bindings;
  std::set<uint32_t> builtIns;
  struct Variable {
    uint32_t id, type, storage;
  };
  std::vector<Variable> variables;
  std::vector<ForeignResource> out;
  // Header: magic, version, generator, bound, schema. Then instructions: (words << 16) | opcode.
  for (size_t at = 5; at < words.size();) {
    const uint32_t count = words[at] >> 16, op = words[at] & 0xFFFF;
    if (count == 0 || at + count > words.size()) break;  // malformed: stop (the driver rejects it)
    const uint32_t* w = &words[at];
    if (op == kOpName && count >= 3) names[w[1]] = literalString(words, at + 2, at + count);
    if (op == kOpTypePointer && count >= 4) pointee[w[1]] = w[3];
    if (op == kOpDecorate && count >= 3) {
      if (w[2] == kDecorationBuiltIn) builtIns.insert(w[1]);
      if (w[2] == kDecorationDescriptorSet && count >= 4) sets[w[1]] = w[3];
      if (w[2] == kDecorationBinding && count >= 4) bindings[w[1]] = w[3];
    }
    if (op == kOpVariable && count >= 4) variables.push_back({w[2], w[1], w[3]});
    if (op == kOpControlBarrier || op == kOpMemoryBarrier) out.push_back({"", "a barrier"});
    at += count;
  }
  auto nameOf = [&](const Variable& v) {
    if (auto it = names.find(v.id); it != names.end() && !it->second.empty()) return it->second;
    if (auto p = pointee.find(v.type); p != pointee.end())
      if (auto it = names.find(p->second); it != names.end()) return it->second;
    return std::string();
  };
  std::map<DescriptorSlot, std::vector<std::string>> declared;  // non-alias variables per slot, in order
  for (const Variable& v : variables) {
    const std::string name = nameOf(v);
    switch (v.storage) {
      case kInput:
      case kOutput:
        if (!builtIns.count(v.id)) out.push_back({name, "an interface variable (in/out)"});
        break;
      case kWorkgroup:
      case kCrossWorkgroup: out.push_back({name, "shared memory"}); break;
      case kUniformConstant:
      case kUniform:
      case kImage:
      case kStorageBuffer: {
        const DescriptorSlot slot{sets.count(v.id) ? sets[v.id] : 0u, bindings.count(v.id) ? bindings[v.id] : 0u};
        const std::string where = "set " + std::to_string(slot.set) + ", binding " + std::to_string(slot.binding);
        if (!layout.count(slot))
          out.push_back({name, "a descriptor at " + where + ", which the pipeline layout does not have"});
        else if (!aliases.count(name))
          declared[slot].push_back(name);
        break;
      }
      default: break;  // Function, Private, PushConstant (a second push-constant block is a GLSL error)
    }
  }
  // A BRDF's text comes before the integrator's declarations (program_assembler.h), so of two
  // variables at one slot the first is the BRDF's.
  for (const auto& [slot, vars] : declared)
    if (vars.size() > 1)
      out.push_back({vars.front(), "a descriptor at set " + std::to_string(slot.set) + ", binding " +
                                       std::to_string(slot.binding) + ", which the integrator already uses"});
  return out;
}

}  // namespace brdfa
