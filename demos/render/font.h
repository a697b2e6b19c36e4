#pragma once
// A 5 x 7 pixel font for the HUD and the legend (upper case, digits, a little punctuation; lower
// case is shown as upper case). Drawn as small quads, so it needs no texture and no font library.

#include <array>
#include <cstdint>

namespace torsion::render {

constexpr int kGlyphWidth = 5;
constexpr int kGlyphHeight = 7;

/// Rows top to bottom; bit 4 is the leftmost column. Unknown characters give a hollow box.
const std::array<std::uint8_t, kGlyphHeight>& glyph(char c);

}  // namespace torsion::render
