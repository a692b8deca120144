// Number formatting shared by the overlay and the log panel.
export const pct = (x) => (x == null ? 'n/a' : `${(x * 100).toFixed(2)}%`);
/** A relative error as a percentage with two significant digits at most: 13%, 1.3%, 0.13%. */
export const errPct = (x) => {
  if (x == null || !Number.isFinite(x)) return 'n/a';
  const p = x * 100;
  if (p === 0) return '0%';
  const digits = p >= 10 ? 0 : p >= 1 ? 1 : Math.min(4, 1 - Math.floor(Math.log10(p)));
  return `${p.toFixed(digits)}%`;
};
export const fixed = (x, digits = 1) => (x == null || !Number.isFinite(x) ? 'n/a' : x.toFixed(digits));
export const seconds = (ms) => (ms == null ? 'n/a' : `${(ms / 1000).toFixed(1)} s`);
/** Two significant digits, in exponent form outside 0.01..10^4: plot labels. */
export const sig = (x) => {
  if (x == null || !Number.isFinite(x)) return 'n/a';
  const a = Math.abs(x);
  return a !== 0 && (a < 0.01 || a >= 1e4) ? x.toExponential(1) : String(Number(x.toPrecision(2)));
};
