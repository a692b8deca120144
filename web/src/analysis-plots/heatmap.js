// A heat map of a grid of numbers and its colour bar, on a 2D canvas. BRDF values span decades:
// a log scale maps the positive values of the top `decades` decades.
import { sequential } from './colormap.js';
import { sig } from '../format.js';

const finite = (v) => v != null && Number.isFinite(v);

/**
 * {lo, hi, log, over} over the grid's values (positive ones for log), or null when there are
 * none. Cells for which skip(row, col) holds do not set the range (they saturate when outside
 * it); `over` says whether any value lies above hi.
 */
export function valueScale(grid, log, decades = 4, skip = () => false) {
  let lo = Infinity;
  let hi = -Infinity;
  let top = -Infinity;
  grid.forEach((row, r) => row.forEach((v, c) => {
    if (!finite(v) || (log && v <= 0)) return;
    top = Math.max(top, v);
    if (skip(r, c)) return;
    lo = Math.min(lo, v);
    hi = Math.max(hi, v);
  }));
  if (!(hi >= lo)) return null;
  if (log) lo = Math.max(lo, hi * 10 ** -decades);
  if (hi === lo) hi = log ? lo * 10 : lo + (Math.abs(lo) || 1);   // a constant grid still gets a bar
  return { lo, hi, log, over: top > hi };
}

/** Where v falls on the scale, 0..1 (clamped). */
export function position({ lo, hi, log }, v) {
  const p = log ? (Math.log10(Math.max(v, lo)) - Math.log10(lo)) / (Math.log10(hi) - Math.log10(lo)) : (v - lo) / (hi - lo);
  return Math.min(1, Math.max(0, p));
}

/** Tick marks of a colour bar: its ends and middle, or each decade of a log scale; the top one says "≥" when values saturate. */
export function scaleTicks(scale) {
  const { lo, hi, log, over } = scale;
  let values = [lo, log ? Math.sqrt(lo * hi) : (lo + hi) / 2, hi];
  if (log) {
    const decades = [];
    for (let e = Math.ceil(Math.log10(lo)); e <= Math.floor(Math.log10(hi)); ++e) decades.push(10 ** e);
    if (decades.length >= 2) values = decades;
  }
  const ticks = values.map((v) => ({ pos: position(scale, v), label: sig(v) }));
  return over ? [...ticks.filter((t) => t.pos < 0.9), { pos: 1, label: `≥ ${sig(hi)}` }] : ticks;
}

/** grid[row][col] into rect {x, y, w, h} of g: column 0 on the left, row 0 at the bottom; null cells stay empty. */
export function drawHeatmap(g, rect, grid, scale, map = sequential) {
  const rows = grid.length;
  const cols = grid[0]?.length || 0;
  if (!rows || !cols) return;
  const img = new ImageData(cols, rows);
  for (let r = 0; r < rows; ++r) {
    for (let c = 0; c < cols; ++c) {
      const v = grid[r][c];
      if (!finite(v)) continue;
      const i = ((rows - 1 - r) * cols + c) * 4;
      const [R, G, B] = map(position(scale, v));
      img.data[i] = R;
      img.data[i + 1] = G;
      img.data[i + 2] = B;
      img.data[i + 3] = 255;
    }
  }
  const cells = document.createElement('canvas');
  cells.width = cols;
  cells.height = rows;
  cells.getContext('2d').putImageData(img, 0, 0);
  g.imageSmoothingEnabled = false;   // one cell, one sample: no blending into the empty cells
  g.drawImage(cells, rect.x, rect.y, rect.w, rect.h);
}

/**
 * A colour bar in rect: `map(p)` for p in 0..1, from bottom to top (vertical) or left to right,
 * with ticks [{pos, label}] beside it (right of a vertical bar, below a horizontal one).
 */
export function drawColourBar(g, rect, map, ticks, vertical = true) {
  const n = Math.round(vertical ? rect.h : rect.w);
  for (let i = 0; i < n; ++i) {
    const [r, gr, b] = map(vertical ? 1 - i / (n - 1) : i / (n - 1));
    g.fillStyle = `rgb(${r},${gr},${b})`;
    if (vertical) g.fillRect(rect.x, rect.y + i, rect.w, 1);
    else g.fillRect(rect.x + i, rect.y, 1, rect.h);
  }
  g.strokeStyle = '#888';
  g.strokeRect(rect.x + 0.5, rect.y + 0.5, rect.w - 1, rect.h - 1);
  g.fillStyle = '#333';
  g.textBaseline = vertical ? 'middle' : 'top';
  for (const t of ticks) {
    if (vertical) {
      const y = rect.y + (1 - t.pos) * rect.h;
      g.textAlign = 'left';
      g.fillRect(rect.x + rect.w, y, 3, 1);
      g.fillText(t.label, rect.x + rect.w + 5, y);
    } else {
      const x = rect.x + t.pos * rect.w;
      g.textAlign = t.pos <= 0 ? 'left' : t.pos >= 1 ? 'right' : 'center';
      g.fillRect(x, rect.y + rect.h, 1, 3);
      g.fillText(t.label, x, rect.y + rect.h + 5);
    }
  }
}
