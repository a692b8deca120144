// Colour maps of the plots, t in 0..1 (sequential) or -1..1 (diverging) to sRGB bytes [r, g, b].

// Dark to light through purple and orange: luminance rises monotonically, so the map reads in
// grey too. Stops chosen for this project, interpolated linearly.
const STOPS = [[12, 7, 40], [70, 30, 130], [170, 50, 110], [240, 120, 40], [250, 240, 160]];

export function sequential(t) {
  const x = Math.min(1, Math.max(0, t)) * (STOPS.length - 1);
  const i = Math.min(STOPS.length - 2, Math.floor(x));
  const f = x - i;
  return STOPS[i].map((a, k) => Math.round(a + (STOPS[i + 1][k] - a) * f));
}

const srgb8 = (c) => Math.round(255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055));

/** The server's difference map (renderer/src/render/frame_difference.cpp): blue, white, red, linear before sRGB. */
export function diverging(t) {
  const s = Math.min(1, Math.max(-1, t));
  const a = Math.abs(s);
  return [s > 0 ? 1 : 1 - a, 1 - a, s < 0 ? 1 : 1 - a].map(srgb8);
}
