// The image slice (Burley 2012, as the BRDF Explorer draws it): f over theta_h (across) and
// theta_d (up) at one phi_d, as a heat map with its colour bar. A dashed curve marks where the
// light is at theta_i, so the slice shows where the polar plot's incidence lies.
import { prepare, widthOf } from './canvas.js';
import { valueScale, scaleTicks, drawHeatmap, drawColourBar } from './heatmap.js';
import { sequential } from './colormap.js';
import { luminance } from '../analysis-series.js';

const HEIGHT = 215;
const rad = (d) => (d * Math.PI) / 180;

/** L's cosine to N for (theta_h, theta_d, phi_d): renderer/src/analysis/brdf_plots.cpp, L = turn(D). */
const lightCos = (th, td, pd) => Math.cos(rad(td)) * Math.cos(rad(th)) - Math.sin(rad(td)) * Math.cos(rad(pd)) * Math.sin(rad(th));

/** Points (theta_h, theta_d) where L is at theta_i: the first crossing along theta_d per theta_h. */
function incidenceCurve(thetaI, pd) {
  const c = Math.cos(rad(thetaI));
  const out = [];
  for (let th = 0; th <= 90; th += 0.5) {
    let prev = lightCos(th, 0, pd) - c;
    let hit = null;
    for (let td = 0.25; td <= 90 && hit == null; td += 0.25) {
      const now = lightCos(th, td, pd) - c;
      if (prev === 0 || prev * now < 0) hit = td - 0.25 * (now / (now - prev));
      prev = now;
    }
    out.push(hit == null ? null : [th, hit]);
  }
  return out;
}

export function drawSlice(canvas, slice, { log, thetaI }) {
  const width = widthOf(canvas);
  const g = prepare(canvas, width, HEIGHT);
  const series = slice?.series?.[0];
  canvas.dataset.drawn = '0';
  if (!series) return;
  const grid = series.values.map((row) => row.map(luminance));
  const hs = slice.axes.theta_h_deg;
  const ds = slice.axes.theta_d_deg;
  // The edges at 90 degrees put L or V on the horizon, where many BRDFs are singular (a 1 / N.L
  // of cos(pi/2) ~ 6e-17 in floating point): they do not set the colour range, they saturate.
  const scale = valueScale(grid, log, 4, (d, h) => ds[d] >= 90 || hs[h] >= 90);
  const side = Math.min(HEIGHT - 36, width - 40 - 80);
  const map = { x: 40, y: 8, w: side, h: side };
  if (!scale) { g.fillText('no values to show (all zero or below the horizon)', map.x, map.y + 20); return; }
  drawHeatmap(g, map, grid, scale);
  drawColourBar(g, { x: map.x + side + 12, y: map.y, w: 12, h: side }, sequential, scaleTicks(scale));

  // Axes: theta_h across, theta_d up, both 0..90 degrees.
  const px = (th) => map.x + ((th - hs[0]) / (hs.at(-1) - hs[0])) * map.w;
  const py = (td) => map.y + map.h - ((td - ds[0]) / (ds.at(-1) - ds[0])) * map.h;
  g.fillStyle = '#333';
  for (const t of [0, 30, 60, 90]) {
    g.textAlign = 'center';
    g.textBaseline = 'top';
    g.fillText(`${t}°`, px(t), map.y + map.h + 3);
    g.textAlign = 'right';
    g.textBaseline = 'middle';
    g.fillText(`${t}°`, map.x - 4, py(t));
  }
  g.textAlign = 'center';
  g.fillText('θh', map.x + map.w / 2 + 30, map.y + map.h + 20);
  g.save();
  g.translate(10, map.y + map.h / 2);
  g.rotate(-Math.PI / 2);
  g.fillText('θd', 0, 0);
  g.restore();

  // Where the light is at theta_i.
  g.strokeStyle = '#fff';
  g.setLineDash([4, 3]);
  g.lineWidth = 1.5;
  g.beginPath();
  let open = false;
  for (const p of incidenceCurve(thetaI, slice.phi_d ?? 90)) {
    if (!p) { open = false; continue; }
    if (open) g.lineTo(px(p[0]), py(p[1])); else g.moveTo(px(p[0]), py(p[1]));
    open = true;
  }
  g.stroke();
  g.setLineDash([]);
  canvas.dataset.drawn = '1';
  canvas.dataset.range = `${scale.lo} ${scale.hi}`;
}
