// Structural checks of encoded images, run before stb_image decodes them. stb_image reads
// zeros past the end of its buffer instead of failing, so on its own it accepts a truncated
// JPEG (a grey lower half) and can loop forever on a truncated run-length HDR; and it skips
// PNG checksums, so damaged pixel data may decode silently. These walks find each of those
// and say what is wrong, so a damaged upload is refused with a reason.
#pragma once

#include <cstdint>
#include <functional>
#include <string_view>

#include "brdfa/result.h"

namespace brdfa {

// One chunk of a PNG (PNG spec 5.3): its 4-byte type, its data, and the CRC stored after them.
struct PngChunk {
  std::string_view type;
  std::string_view data;  // directly follows `type` in the file, as the CRC covers both
  uint32_t storedCrc = 0;
};

// How a walk over a PNG's chunks ended: at IEND, because `visit` said stop, or at data that
// cannot be a chunk (the header or the chunk `type` runs past the end, or no IEND at all).
struct PngWalk {
  enum class End { Iend, Stopped, TruncatedHeader, TruncatedChunk, NoIend } end;
  std::string_view type;  // the chunk that runs past the end (TruncatedChunk)
};

// Visits the chunks after the 8-byte signature in order, IEND included, while `visit` returns
// true. Never reads outside `bytes`; checks no CRC (the visitor may).
PngWalk walkPngChunks(std::string_view bytes, const std::function<bool(const PngChunk&)>& visit);

// PNG: every chunk lies inside the data, its CRC-32 matches, and IEND is reached.
Result<void> checkPngStructure(std::string_view bytes);

// JPEG: the marker segments and entropy-coded scans lie inside the data up to the
// end-of-image marker (ITU-T T.81, annex B).
Result<void> checkJpegStructure(std::string_view bytes);

// Radiance RGBE of `width` x `height` (from its header): the header's blank line and
// resolution line are present and the pixel data holds every scanline, each run-length
// scanline well formed (Ward, "Real Pixels", Graphics Gems II; the layout stb_image reads).
Result<void> checkRgbeStructure(std::string_view bytes, int width, int height);

}  // namespace brdfa
