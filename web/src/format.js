// Number formatting shared by the overlay and the log panel.
export const pct = (x) => (x == null ? 'n/a' : `${(x * 100).toFixed(2)}%`);
export const fixed = (x, digits = 1) => (x == null || !Number.isFinite(x) ? 'n/a' : x.toFixed(digits));
export const seconds = (ms) => (ms == null ? 'n/a' : `${(ms / 1000).toFixed(1)} s`);
