// The Analysis tab's overlays: series {key, brdf, params, label, color}, as the analysis
// endpoints take them (docs/api.md "Analysis"), and the presets that put the thesis's component
// figures one click away.
import { defaults } from './param-controls.js';

export const MAX_SERIES = 8;   // the endpoints take 1..8 series
const PALETTE = ['#1f6fd1', '#d1491f', '#2a9d3a', '#8b3fc9', '#c99a00', '#0f9ab0', '#c93f7f', '#555555'];

/** Blinn-Phong exponent equivalent to Beckmann slope m (Walter et al., EGSR 2007, section 5.2): n = 2/m^2 - 2. */
export const blinnExponent = (m) => 2 / (m * m) - 2;

const M = 0.3;   // the thesis's roughness for its component figures
export const PRESETS = {
  D: [{ brdf: 'D_beckmann', params: { m: M } }, { brdf: 'D_ggx', params: { alpha: M } },
    { brdf: 'D_blinn', params: { n: Number(blinnExponent(M).toFixed(1)) } }],
  G: [{ brdf: 'G_smith_ggx', params: { alpha: M } }, { brdf: 'G_smith_beckmann', params: { m: M } },
    { brdf: 'G_cook_torrance' }, { brdf: 'G_torrance_sparrow' }, { brdf: 'G_implicit' }],
  F: [{ brdf: 'F_schlick' }, { brdf: 'F_dielectric' }, { brdf: 'F_conductor' }],
};

let nextKey = 1;

/**
 * A new series of BRDF `name` (its declarations from `library`). Its values: `params` where
 * given; else those of the session's selected object when that object uses this BRDF; else the
 * file's defaults. Its colour is the first one no series in `taken` has.
 */
export function makeSeries(name, { library, object, taken, params }) {
  const decls = library.find((b) => b.name === name)?.params || [];
  const values = params ? { ...defaults(decls), ...params }
    : object?.brdf === name ? { ...defaults(decls), ...object.params } : defaults(decls);
  const used = new Set(taken.map((s) => s.color));
  const color = PALETTE.find((c) => !used.has(c)) || PALETTE[taken.length % PALETTE.length];
  const twins = taken.filter((s) => s.brdf === name).length;
  return { key: nextKey++, brdf: name, params: values, decls, color, label: twins ? `${name} (${twins + 1})` : name };
}

/** What the endpoints take of a series. */
export const request = (s) => ({ brdf: s.brdf, params: s.params, label: s.label });

/** Rec. 709 luminance of an [r, g, b] value; null for no value (null, or [null, null, null] as a slice sends it). */
export const luminance = (v) => (v?.[0] == null ? null : 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]);
