// Names of uploads as other users see them: the last path component, valid UTF-8,
// without controls or the invisible format characters that reorder or hide text.
#include <gtest/gtest.h>

#include "storage/asset_store.h"

namespace brdfa::server {
namespace {

TEST(UploadNames, LoseBidiControlsZeroWidthAndControlCharacters) {
  // U+202E RIGHT-TO-LEFT OVERRIDE would show "photo\u202Egpj.exe" as "photoexe.jpg".
  EXPECT_EQ(sanitizeUploadFileName("photo\xE2\x80\xAEgpj.exe"), "photogpj.exe");
  // Isolates (U+2066..2069), embeddings (U+202A..202D), marks (U+200E/F), zero-width (U+200B..D),
  // BOM (U+FEFF), soft hyphen (U+00AD), a C1 control (U+0085), a tag (U+E0041).
  EXPECT_EQ(sanitizeUploadFileName("a\xE2\x81\xA6"
                                   "b\xE2\x81\xA9"
                                   "c\xE2\x80\xAA"
                                   "d\xE2\x80\x8E"
                                   "e\xE2\x80\x8B"
                                   "f\xEF\xBB\xBF"
                                   "g\xC2\xAD"
                                   "h\xC2\x85"
                                   "i\xF3\xA0\x81\x81"
                                   "j.png"),
            "abcdefghij.png");
  EXPECT_EQ(sanitizeUploadFileName("tab\there\nnew.obj"), "tabherenew.obj");
  // Ordinary non-ASCII text stays: accents, CJK, emoji, right-to-left letters themselves.
  EXPECT_EQ(
      sanitizeUploadFileName("caf\xC3\xA9 \xE5\xA4\xA9\xE7\xA9\xBA \xF0\x9F\x8C\x85 \xD7\xA9\xD7\x9E\xD7\xA9.hdr"),
      "caf\xC3\xA9 \xE5\xA4\xA9\xE7\xA9\xBA \xF0\x9F\x8C\x85 \xD7\xA9\xD7\x9E\xD7\xA9.hdr");
  // Paths: the last component only.
  EXPECT_EQ(sanitizeUploadFileName("C:\\\\Users\\x/../sky.exr"), "sky.exr");
}

}  // namespace
}  // namespace brdfa::server
