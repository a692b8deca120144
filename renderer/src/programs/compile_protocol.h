// The wire format between the renderer and its compile workers (compile_pool.h): one request,
// one reply, each a frame of a u32 byte count and that many bytes, little-endian as the host
// (both ends are the same build on the same machine).
//   request: u32 stage, then the GLSL source
//   reply:   u32 ok; ok: f64 compileMs, u32 word count, the words, diagnostics (the warnings);
//            else: u32 error code, string message, diagnostics
//   diagnostics: u32 count, then per item i32 line, i32 column, string severity, string message
//   string: u32 byte count, bytes
#pragma once

#include <cstdint>
#include <optional>
#include <initializer_list>
#include <string>
#include <string_view>

#include "brdfa/result.h"

#include "programs/glsl_compiler.h"

namespace brdfa::compile_protocol {

std::string encodeRequest(ShaderStage stage, const std::string& source);
// False when the bytes are not a request.
bool decodeRequest(const std::string& frame, ShaderStage& stage, std::string& source);

std::string encodeReply(const Result<SpirvBinary>& result);
// nullopt when the bytes are not a reply.
std::optional<Result<SpirvBinary>> decodeReply(const std::string& frame);

// Blocking frame I/O on a socket or pipe; false on EOF or error. Writes never raise SIGPIPE.
bool writeFrame(int fd, const std::string& payload);
// One frame whose payload is `parts` one after the other, sent without joining them first (a
// frame's pixels go out straight from where they were read back).
bool writeFrameParts(int fd, std::initializer_list<std::string_view> parts);
bool readFrame(int fd, std::string& payload, uint32_t maxBytes);

}  // namespace brdfa::compile_protocol
