// The polar plot: f (luminance) against the view angle in one plane, drawn as a polar curve
// over the upper half plane (the normal up, the incident side on the left), one curve a series.
// Log scale: radius by decade, the top three decades of the largest value.
import { prepare, widthOf } from './canvas.js';
import { sig } from '../format.js';
import { luminance } from '../analysis-series.js';

const HEIGHT = 215;
const DECADES = 3;
const rad = (d) => (d * Math.PI) / 180;

export function drawPolar(canvas, polar, { plane, log, thetaI, colors }) {
  const width = widthOf(canvas);
  const g = prepare(canvas, width, HEIGHT);
  const ox = width / 2;
  const oy = HEIGHT - 22;
  const R = Math.min(width / 2 - 24, HEIGHT - 40);
  const curves = (polar?.series || []).map((s) => (s.values[plane] || []).map(luminance));
  let top = 0;
  for (const c of curves) for (const v of c) if (v > top) top = v;
  const radius = (v) => {
    if (!(v > 0) || !(top > 0)) return 0;
    return log ? Math.max(0, (Math.log10(v / top) + DECADES) / DECADES) * R : (v / top) * R;
  };
  const at = (t, r) => [ox + r * Math.sin(rad(t)), oy - r * Math.cos(rad(t))];

  // Grid: rings (quarters of the largest value, or decades) and spokes every 30 degrees.
  g.strokeStyle = '#ddd';
  g.fillStyle = '#777';
  g.lineWidth = 1;
  const rings = log ? [...Array(DECADES).keys()].map((k) => top / 10 ** k) : [0.25, 0.5, 0.75, 1].map((k) => k * top);
  g.textAlign = 'center';
  g.textBaseline = 'bottom';
  for (const v of rings) {
    const r = radius(v);
    g.beginPath();
    g.arc(ox, oy, r, Math.PI, 2 * Math.PI);
    g.stroke();
    if (top > 0) g.fillText(sig(v), ...at(-80, r + 2));   // near the horizon, where lobes are low
  }
  g.textAlign = 'center';
  for (let t = -90; t <= 90; t += 30) {
    const [x, y] = at(t, R);
    g.beginPath();
    g.moveTo(ox, oy);
    g.lineTo(x, y);
    g.stroke();
    const [lx, ly] = at(t, R + 10);
    g.fillText(`${t}°`, lx, ly + 5);
  }

  // The light (incidence plane only: it lies outside the perpendicular one) and its mirror.
  if (plane === 'incidence') {
    g.setLineDash([5, 4]);
    g.strokeStyle = '#333';
    g.beginPath();
    g.moveTo(...at(-thetaI, R));
    g.lineTo(ox, oy);
    g.stroke();
    g.strokeStyle = '#aaa';
    g.beginPath();
    g.moveTo(ox, oy);
    g.lineTo(...at(thetaI, R));
    g.stroke();
    g.setLineDash([]);
    g.fillStyle = '#333';
    g.fillText('L', ...at(-thetaI - 5, 0.75 * R));
  }

  // One curve a series.
  const thetas = polar?.axes?.theta_deg || [];
  g.lineWidth = 2;
  curves.forEach((c, i) => {
    g.strokeStyle = colors[i] || '#000';
    g.beginPath();
    let open = false;
    c.forEach((v, k) => {
      if (v == null) { open = false; return; }
      const [x, y] = at(thetas[k], radius(v));
      if (open) g.lineTo(x, y); else g.moveTo(x, y);
      open = true;
    });
    g.stroke();
  });
  g.fillStyle = '#333';
  g.textAlign = 'left';
  g.textBaseline = 'top';
  g.fillText(`${plane} plane · θi ${thetaI}° · ${log ? `log, ${DECADES} decades` : 'linear'}`, 4, 2);
  canvas.dataset.curves = String(curves.length);
}
