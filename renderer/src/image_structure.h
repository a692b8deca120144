// Structural checks of encoded images, run before stb_image decodes them. stb_image reads
// zeros past the end of its buffer instead of failing, so on its own it accepts a truncated
// JPEG (a grey lower half) and can loop forever on a truncated run-length HDR; and it skips
// PNG checksums, so damaged pixel data may decode silently. These walks find each of those
// and say what is wrong, so a damaged upload is refused with a reason.
#pragma once

#include <string_view>

#include "brdfa/result.h"

namespace brdfa {

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
