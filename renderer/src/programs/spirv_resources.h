// What a compiled program declares, read from its SPIR-V: a BRDF file's text is
// compiled into the integrator's program, and must not add resources of its own. Checking the
// compiled module, not the spelling, catches every way of writing them (macros included).
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace brdfa {

struct DescriptorSlot {
  uint32_t set = 0, binding = 0;
  bool operator<(const DescriptorSlot& o) const { return set != o.set ? set < o.set : binding < o.binding; }
};

// Something a program declares that its pipeline layout does not provide for.
struct ForeignResource {
  std::string name;  // the variable's name, else its block type's; may be empty
  std::string what;  // e.g. "a descriptor at set 0, binding 3 that the integrator already uses"
};

// Every descriptor must sit at a slot of `layout`, each slot declared once (variables named in
// `aliases` may share a slot with another); no shared (workgroup) memory, no barriers, no
// interface variables but built-ins. Returns what breaks these rules; of two variables at one
// slot, the first declared is named.
std::vector<ForeignResource> foreignResources(const std::vector<uint32_t>& words,
                                              const std::set<DescriptorSlot>& layout,
                                              const std::set<std::string>& aliases);

}  // namespace brdfa
