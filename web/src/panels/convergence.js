// Convergence: the session's relative error against render time on log-log axes (uPlot), with
// the server's least-squares line and its slope (Monte Carlo: about -0.5), and the comparison of
// sampling strategies at equal time (POST /api/jobs/convergence) as a table.
// uPlot and its stylesheet load when the tab is first shown, never before the first frame.
import * as api from '../api.js';
import { state, on } from '../state.js';
import { errPct, seconds } from '../format.js';
import { loadUplot } from '../uplot.js';

const JOB_POLL_MS = 500;

/** [seconds, rel_error, fit] columns of the points with both > 0 (log axes). */
function columns(conv) {
  const pts = (conv?.points || []).filter((p) => p.elapsed_ms > 0 && p.rel_error > 0);
  const xs = pts.map((p) => p.elapsed_ms / 1000);
  const ys = pts.map((p) => p.rel_error);
  const fit = conv?.fit;
  // log(err) = intercept + slope * log(t - offset): the first pass (driver JIT, raster) is off.
  const off = fit?.time_offset_ms || 0;
  const last = pts.length ? pts[pts.length - 1].elapsed_ms - off : 0;
  // The line over the stretch it was fitted on (after the first 10% of the time).
  const line = pts.map((p) => (fit && p.elapsed_ms - off > 0 && p.elapsed_ms - off >= 0.1 * last
    ? Math.exp(fit.intercept + fit.slope * Math.log(p.elapsed_ms - off)) : null));
  return [xs, ys, line];
}

export function mountConvergence(el) {
  const $ = (c) => el.querySelector(c);
  const host = $('.conv-plot');
  const fitText = $('.conv-fit');
  const info = $('.conv-info');
  let plot = null;
  let creating = false;
  const shown = () => !el.closest('.tab-page')?.hidden;

  async function draw() {
    const conv = state.convergence;
    if (!shown() || !conv || conv.session !== state.session) return;
    const data = columns(conv);
    host.dataset.points = String(data[0].length);
    const fit = conv.fit;
    fitText.textContent = fit
      ? `slope ${fit.slope.toFixed(2)} (${fit.points_used} points)` +
        (conv.target_error != null && conv.predicted_ms != null
          ? ` · ${errPct(conv.target_error)} at ~${seconds(conv.predicted_ms)}` : '')
      : 'slope: needs 3 measurements';
    const end = conv.converged ? ' · converged' : conv.max_samples_reached ? ' · max spp' : '';
    info.textContent = `${conv.sampling}${conv.estimator ? ` → ${conv.estimator}` : ''} · ${conv.spp} spp · ` +
      `${seconds(conv.elapsed_ms)}${end}${(conv.warnings || []).length ? ` · ${conv.warnings.join('; ')}` : ''}`;
    if (plot) { plot.setData(data); return; }
    if (creating) return;
    creating = true;
    try {
      const UPlot = await loadUplot();
      plot = new UPlot({
        width: Math.max(300, host.clientWidth),
        height: 260,
        scales: { x: { time: false, distr: 3 }, y: { distr: 3 } },
        axes: [
          { label: 'render time (s)' },
          // Log axes label only some ticks: the others come as null.
          { label: 'relative error', size: 60, values: (u, vals) => vals.map((v) => (v == null ? '' : errPct(v))) },
        ],
        series: [
          { label: 'time', value: (u, v) => (v == null ? '–' : `${v.toFixed(2)} s`) },
          { label: 'rel_error', stroke: '#2a6fc9', width: 1.5, points: { show: true, size: 4 }, value: (u, v) => (v == null ? '–' : errPct(v)) },
          { label: 'fit', stroke: '#d2691e', dash: [6, 4], width: 1.5, points: { show: false }, value: (u, v) => (v == null ? '–' : errPct(v)) },
        ],
      }, columns(state.convergence), host);
    } catch (e) {
      info.textContent = `plot: ${e.message}`;
    } finally {
      creating = false;
    }
  }
  on('convergence', draw);
  on('tab', draw);
  window.addEventListener('resize', () => { if (plot && shown()) plot.setSize({ width: Math.max(300, host.clientWidth), height: 260 }); });

  // ---- sampling strategies at equal time ----
  const run = $('.cmp-run');
  const cancel = $('.cmp-cancel');
  const bar = $('.cmp-progress');
  const status = $('.cmp-status');
  const body = $('.cmp-results tbody');
  let job = null;

  function showResult(result) {
    body.replaceChildren(...result.modes.map((m) => {
      const tr = document.createElement('tr');
      if (m.sampling === result.best) tr.className = 'best';
      const f = m.final || {};
      const ratio = m.equal_time_relmse_vs_cosine;
      for (const v of [m.sampling, m.estimator || '', f.spp ?? '', errPct(f.rel_error), errPct(f.true_rel_error),
        ratio == null ? 'n/a' : `${ratio.toFixed(2)}x`]) {
        const td = document.createElement('td');
        td.textContent = String(v);
        tr.append(td);
      }
      return tr;
    }));
  }

  async function follow(id) {
    while (job === id) {
      let j;
      try {
        j = await api.getJob(id);
      } catch (e) {
        status.textContent = e.message;
        break;
      }
      bar.value = j.progress;
      status.textContent = j.state === 'failed' ? `failed: ${j.error?.message}` : j.state;
      if (j.state === 'done') showResult(j.result);
      if (!['queued', 'running'].includes(j.state)) break;
      await new Promise((r) => setTimeout(r, JOB_POLL_MS));
    }
    if (job === id) job = null;
    run.disabled = false;
    cancel.hidden = true;
  }

  run.addEventListener('click', async () => {
    if (!state.scene) return;
    const time = Number($('.cmp-time').value);
    body.replaceChildren();
    status.textContent = 'starting…';
    try {
      const started = await api.startConvergenceJob({ scene: state.scene, time_ms: time });
      job = started.id;
      run.disabled = true;
      cancel.hidden = false;
      follow(started.id);
    } catch (e) {
      status.textContent = e.message;
    }
  });
  cancel.addEventListener('click', () => { if (job) api.cancelJob(job).catch((e) => { status.textContent = e.message; }); });
}
