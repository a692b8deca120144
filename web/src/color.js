// <input type="color"> speaks #rrggbb; BRDF colours are linear [r, g, b] in 0..1. The picker's
// value is mapped 1:1 (no sRGB decode) so the number a student reads in the .brdf default is
// the number the swatch encodes, as in the BRDF Explorer.
export function toHex(rgb) {
  const c = (x) => Math.round(Math.min(1, Math.max(0, x)) * 255).toString(16).padStart(2, '0');
  return `#${c(rgb[0])}${c(rgb[1])}${c(rgb[2])}`;
}

export function fromHex(hex) {
  const n = parseInt(hex.slice(1), 16);
  return [(n >> 16) & 255, (n >> 8) & 255, n & 255].map((x) => x / 255);
}
