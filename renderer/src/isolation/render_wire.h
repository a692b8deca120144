// The wire format between the server's RemoteRenderer (remote_renderer.h) and its
// brdfa-render-worker: each message is one frame (compile_protocol's u32 byte count, then the
// bytes) holding a u32 byte count, that many bytes of CBOR-encoded JSON, and a binary tail (a frame's
// pixels). The JSON forms of the renderer's value types below are private to this pair of
// processes (the same build), not a public format.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "brdfa/renderer.h"

namespace brdfa::render_wire {

struct Message {
  nlohmann::json head;
  std::string tail;  // binary payload; empty for most messages
};

std::string encode(const Message& message);
// encode() of a message without its tail: the tail's bytes follow it in the frame
// (compile_protocol::writeFrameParts), so a large one need not be copied in.
std::string encodeHead(const nlohmann::json& head);
// False when the bytes are not a message.
bool decode(const std::string& frame, Message& message);

// A BRDF's identity for quarantine: a hash of everything that changes its compiled programs.
std::string programKey(const BrdfDefinition& brdf);

nlohmann::json toJson(const Error& error);
Error errorFromJson(const nlohmann::json& j);
nlohmann::json toJson(const BrdfDefinition& brdf);
BrdfDefinition brdfFromJson(const nlohmann::json& j);
nlohmann::json toJson(const Scene& scene);
Scene sceneFromJson(const nlohmann::json& j);
nlohmann::json toJson(const FrameStats& stats);
FrameStats statsFromJson(const nlohmann::json& j);
nlohmann::json toJson(const RendererOptions& options);
RendererOptions optionsFromJson(const nlohmann::json& j);
nlohmann::json toJson(const DeviceInfo& info);
DeviceInfo deviceFromJson(const nlohmann::json& j);
nlohmann::json toJson(const CompileInfo& info);
CompileInfo compileInfoFromJson(const nlohmann::json& j);
nlohmann::json toJson(const RendererCounters& counters);
RendererCounters countersFromJson(const nlohmann::json& j);
nlohmann::json toJson(const std::vector<DirectionPair>& pairs);
std::vector<DirectionPair> pairsFromJson(const nlohmann::json& j);
nlohmann::json toJson(const std::vector<AlbedoEstimate>& albedo);
std::vector<AlbedoEstimate> albedoFromJson(const nlohmann::json& j);
nlohmann::json toJson(const BrdfCheckReport& report);
BrdfCheckReport brdfReportFromJson(const nlohmann::json& j);
nlohmann::json toJson(const SamplerCheckReport& report);
SamplerCheckReport samplerReportFromJson(const nlohmann::json& j);
nlohmann::json toJson(const EnvironmentSamplerReport& report);
EnvironmentSamplerReport environmentReportFromJson(const nlohmann::json& j);

}  // namespace brdfa::render_wire
