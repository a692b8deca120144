// Directional albedo E(theta_v) (luminance) of each series with its standard error as error
// bars, on a uPlot line plot; a dashed line marks theta_i (by reciprocity, the albedo for light
// from there).
import { loadUplot } from '../uplot.js';
import { luminance } from '../analysis-series.js';
import { widthOf } from './canvas.js';

const HEIGHT = 215;
const W = [0.2126, 0.7152, 0.0722];
/** Luminance's standard error, the channels taken as fully correlated (one set of samples): an upper bound. */
const lumError = (e) => (e == null ? null : W[0] * e[0] + W[1] * e[1] + W[2] * e[2]);

export function albedoPlot(host) {
  let plot = null;
  let thetaI = 30;
  let errors = [];   // per series, per view: the standard error of the luminance
  let strokes = [];
  let generation = 0;   // a newer set() wins over one still loading uPlot

  // Error bars and the theta_i marker, over the series' lines.
  function overlay(u) {
    const g = u.ctx;
    const dpr = window.devicePixelRatio || 1;
    g.save();
    g.lineWidth = dpr;
    errors.forEach((errs, s) => {
      g.strokeStyle = strokes[s];
      const ys = u.data[s + 1];
      errs.forEach((e, i) => {
        if (e == null || ys[i] == null) return;
        const x = u.valToPos(u.data[0][i], 'x', true);
        const y0 = u.valToPos(ys[i] - e, 'y', true);
        const y1 = u.valToPos(ys[i] + e, 'y', true);
        g.beginPath();
        g.moveTo(x, y0); g.lineTo(x, y1);
        g.moveTo(x - 3 * dpr, y0); g.lineTo(x + 3 * dpr, y0);
        g.moveTo(x - 3 * dpr, y1); g.lineTo(x + 3 * dpr, y1);
        g.stroke();
      });
    });
    const x = u.valToPos(thetaI, 'x', true);
    g.strokeStyle = '#333';
    g.setLineDash([5 * dpr, 4 * dpr]);
    g.beginPath();
    g.moveTo(x, u.bbox.top);
    g.lineTo(x, u.bbox.top + u.bbox.height);
    g.stroke();
    g.restore();
  }

  return {
    /** New data (the albedo answer) and the series' colours. */
    async set(albedo, colors) {
      const gen = ++generation;
      const UPlot = await loadUplot();
      if (gen !== generation) return;
      plot?.destroy();
      plot = null;
      const list = albedo?.series || [];
      host.dataset.series = String(list.length);
      if (!list.length) return;
      errors = list.map((s) => s.std_error.map(lumError));
      strokes = colors;
      const data = [albedo.axes.theta_v_deg, ...list.map((s) => s.values.map(luminance))];
      plot = new UPlot({
        width: widthOf(host),
        height: HEIGHT,
        legend: { show: false },   // the tab's own legend names the series
        scales: { x: { time: false, range: [0, 90] }, y: { range: (u, lo, hi) => [0, Math.max(hi * 1.1, 1e-6)] } },
        axes: [{ label: 'θv (degrees)' }, { label: 'albedo (luminance)', size: 56 }],
        series: [{}, ...list.map((s, i) => ({ label: s.label, stroke: colors[i], width: 2, points: { show: true, size: 4 } }))],
        hooks: { draw: [overlay] },
      }, data, host);
    },
    /** Moves the theta_i marker. */
    marker(deg) {
      thetaI = deg;
      plot?.redraw(false);
    },
    resize() { plot?.setSize({ width: widthOf(host), height: HEIGHT }); },
  };
}
