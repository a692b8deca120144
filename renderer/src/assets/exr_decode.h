// OpenEXR images through the OpenEXR library (Debian's 3.1): scanline or tiled files, single-
// or multi-part (part 0 is read), with any of its compressions (NONE, RLE, ZIPS, ZIP, PIZ,
// PXR24, B44(A), DWAA, DWAB). Deep images are refused.
#pragma once

#include <functional>
#include <string_view>

#include "brdfa/result.h"

#include "assets/equirect.h"

namespace brdfa {

// Checks an image's size from its header before its pixels are read (pixel limit, aspect).
using ImageSizeCheck = std::function<Result<void>(int width, int height)>;

// Reads the R, G and B channels (half or float; others, A included, ignored) of an EXR file into
// linear float RGB, row 0 at the top; a file with a luminance channel Y and no colour is read as
// grey. Decodes from memory: no file is opened, and no thread outlives the call. Calls
// `checkSize` with the data window's size after reading the header and before decoding pixels,
// and stops with its error; headers that declare more than the file can hold (attributes, chunk
// tables) are refused before OpenEXR allocates for them. InvalidArgument with the reason
// (OpenEXR's, for a damaged file) when the file cannot be read. Values are returned as stored
// (NaN included).
Result<FloatImage> decodeExr(std::string_view bytes, const ImageSizeCheck& checkSize);

}  // namespace brdfa
