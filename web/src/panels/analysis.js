// Analysis tab: the BRDF Explorer's plots of one or more series (BRDFs or parameter sets of
// one), from POST /api/analysis/{polar,lobe,albedo,slice}: polar plot, 3D lobe, albedo with
// error bars, image slice. A theta_i slider, a legend to add, choose and remove series, the
// chosen series' parameter sliders, and presets for the thesis's D, G and F figures.
// Requests are cheap (no recompile for new values) and go out as the sliders move: one at a
// time, the latest state winning (coalesce.js); a plot is fetched again only when what it
// depends on changed (theta_i moves the polar plot and the lobe; albedo and slice only mark it).
import * as api from '../api.js';
import { state, on } from '../state.js';
import { coalesce } from '../coalesce.js';
import { paramControls } from '../param-controls.js';
import { MAX_SERIES, PRESETS, makeSeries, request } from '../analysis-series.js';
import { drawPolar } from '../analysis-plots/polar.js';
import { drawSlice } from '../analysis-plots/slice.js';
import { albedoPlot } from '../analysis-plots/albedo.js';
import { sig } from '../format.js';

const KINDS = ['polar', 'lobe', 'slice', 'albedo'];   // the quick ones first
const RETRY_MS = 1000;   // after 503 busy (analyses share the one-shot render queue)

// Constant markup, parsed once: no value is ever interpolated into it (names go in as text).
const MARKUP = `
  <div class="row">
    <label title="the light's polar angle: the polar plot and the lobe are for it; albedo and slice mark it">θ<sub>i</sub>
      <input type="range" class="an-theta" min="0" max="89" step="1" value="30"></label><output class="an-theta-out">30°</output>
    <label>plane <select class="an-plane"><option value="incidence">incidence</option><option value="perpendicular">perpendicular</option></select></label>
    <label title="polar plot: three decades; slice: four"><input type="checkbox" class="an-log"> log scale</label>
    <span class="an-status hint" role="status"></span>
  </div>
  <div class="row">
    <span>overlay</span>
    <button type="button" class="an-preset" data-preset="D" title="D_beckmann m 0.3, D_ggx alpha 0.3, D_blinn n 20.2 (= 2/m² − 2)">D terms</button>
    <button type="button" class="an-preset" data-preset="G" title="G_smith_ggx, G_smith_beckmann (0.3), G_cook_torrance, G_torrance_sparrow, G_implicit">G terms</button>
    <button type="button" class="an-preset" data-preset="F" title="F_schlick, F_dielectric, F_conductor (their defaults)">F terms</button>
    <label>BRDF <select class="an-add-brdf"></select></label>
    <button type="button" class="an-add" title="values: the selected object's when it uses this BRDF, else the file's defaults">add</button>
    <button type="button" class="an-clear">clear</button>
  </div>
  <ul class="an-legend" aria-label="series"></ul>
  <div class="an-params params-list"></div>
  <div class="an-grid">
    <figure><figcaption>Polar plot of f</figcaption><canvas class="an-polar"></canvas></figure>
    <figure><figcaption>3D lobe of f <span class="an-lobe-max hint"></span></figcaption><div class="an-lobe"></div></figure>
    <figure><figcaption>Directional albedo ± standard error</figcaption><div class="an-albedo"></div></figure>
    <figure><figcaption>Slice (φd 90°) <span class="an-slice-label hint"></span></figcaption><canvas class="an-slice"></canvas></figure>
  </div>`;

export function mountAnalysis(el) {
  el.innerHTML = MARKUP;
  const $ = (c) => el.querySelector(c);
  const theta = $('.an-theta');
  const status = $('.an-status');
  const legend = $('.an-legend');
  const albedo = albedoPlot($('.an-albedo'));
  let lobe = null;   // three.js loads with the tab's first showing
  let series = [];
  let chosen = null;   // key of the series whose sliders and slice are shown
  const answers = {};  // kind -> {answer, colors}
  const sent = {};     // kind -> the body of the answer shown
  let retry = 0;

  const shown = () => !el.closest('.tab-page')?.hidden;
  const thetaI = () => Number(theta.value);
  const snapshot = () => ({ series: series.map((s) => ({ ...s })), thetaI: thetaI(), chosen });
  const bodies = {
    polar: (s) => ({ series: s.series.map(request), theta_i: s.thetaI }),
    lobe: (s) => ({ series: s.series.map(request), theta_i: s.thetaI }),
    albedo: (s) => ({ series: s.series.map(request) }),
    slice: (s) => {
      const one = s.series.find((x) => x.key === s.chosen) || s.series[0];
      return { series: [request(one)], phi_d: 90, color: one.color };
    },
  };

  /** The request of one plot for a snapshot, and its key (what it depends on). */
  const requestOf = (kind, snap) => {
    const { color, ...wire } = bodies[kind](snap);
    return { wire, key: JSON.stringify(wire), color };
  };
  const figure = (kind) => el.querySelector(`.an-${kind}`).closest('figure');
  let latest = null;   // the newest snapshot asked for
  const dim = (kind) => figure(kind).classList.toggle('stale', !!latest?.series.length && sent[kind] !== requestOf(kind, latest).key);

  function draw(kind) {
    const got = answers[kind];
    const log = $('.an-log').checked;
    if (kind === 'polar') drawPolar($('.an-polar'), got?.answer, { plane: $('.an-plane').value, log, thetaI: got?.answer?.theta_i ?? thetaI(), colors: got?.colors || [] });
    if (kind === 'slice') {
      drawSlice($('.an-slice'), got?.answer, { log, thetaI: thetaI() });
      $('.an-slice-label').textContent = got?.answer?.series?.[0]?.label || '';
    }
    if (kind === 'albedo') albedo.set(got?.answer, got?.colors || []).then(() => albedo.marker(thetaI()));
    if (kind === 'lobe' && lobe) {
      const top = lobe.set(got?.answer, got?.colors || []);
      $('.an-lobe').dataset.thetaI = String(got?.answer?.theta_i ?? '');
      $('.an-lobe-max').textContent = got?.answer ? `(largest f ${sig(top)})` : '';
    }
  }

  // One request at a time; a newer state waiting makes the rest of this round stale.
  const refresh = coalesce(async (snap) => {
    const times = [];
    for (const kind of KINDS) {
      if (refresh.waiting()) return;
      if (!snap.series.length) { answers[kind] = null; delete sent[kind]; draw(kind); continue; }
      const { wire, key } = requestOf(kind, snap);
      if (sent[kind] === key) continue;
      try {
        const answer = await api.analysis(kind, wire);
        answers[kind] = { answer, colors: kind === 'slice' ? [requestOf(kind, snap).color] : snap.series.map((s) => s.color) };
        sent[kind] = key;
        times.push(`${kind} ${Math.round(answer.ms)} ms`);
        if (kind === 'polar') showNotes(answer);
        draw(kind);
        dim(kind);
      } catch (e) {
        status.textContent = `${kind}: ${e.message}`;
        if (e.status === 503) { clearTimeout(retry); retry = setTimeout(update, RETRY_MS); }
        return;
      }
    }
    if (times.length) status.textContent = times.join(' · ');
  });
  // A plot whose request changed is dimmed until its answer is drawn.
  const update = () => {
    if (!shown()) return;
    latest = snapshot();
    KINDS.forEach(dim);
    refresh(latest);
  };

  // ---- the legend: one entry a series (choose it: its sliders and its slice; remove it) ----
  function showLegend() {
    legend.replaceChildren(...series.map((s) => {
      const li = document.createElement('li');
      li.className = s.key === chosen ? 'chosen' : '';
      li.dataset.key = String(s.key);
      const pick = document.createElement('button');
      pick.type = 'button';
      pick.className = 'an-pick';
      const swatch = document.createElement('i');
      swatch.className = 'swatch';
      swatch.style.background = s.color;
      pick.append(swatch, s.label);   // the label (a BRDF name) as text
      pick.title = 'show its parameters and its slice';
      pick.addEventListener('click', () => { chosen = s.key; showLegend(); showParams(); update(); });
      const remove = document.createElement('button');
      remove.type = 'button';
      remove.className = 'an-remove';
      remove.textContent = '×';
      remove.setAttribute('aria-label', `remove ${s.label}`);
      remove.addEventListener('click', () => {
        series = series.filter((x) => x !== s);
        if (chosen === s.key) chosen = series[0]?.key ?? null;
        changed();
      });
      const notes = document.createElement('span');
      notes.className = 'an-notes';
      notes.textContent = (s.notes || []).join('; ');
      li.append(pick, remove, notes);
      return li;
    }));
    legend.dataset.count = String(series.length);
    $('.an-add').disabled = series.length >= MAX_SERIES;
  }
  // What the server clamped (values outside a BRDF's range), beside the series it concerns.
  function showNotes(answer) {
    answer.series.forEach((a, i) => { if (series[i]?.label === a.label) series[i].notes = a.notes; });
    showLegend();
  }

  function showParams() {
    const s = series.find((x) => x.key === chosen);
    const host = $('.an-params');
    if (!s) { host.replaceChildren(); return; }
    paramControls(host, s.decls, s.params, (values) => { s.params = values; update(); });
  }

  function changed() {
    showLegend();
    showParams();
    update();
  }

  function add(name, params) {
    if (series.length >= MAX_SERIES) return;
    if (!state.library.some((b) => b.name === name)) { status.textContent = `${name} is not in the library`; return; }
    const s = makeSeries(name, { library: state.library, object: state.scene?.objects?.[state.selected], taken: series, params });
    series.push(s);
    chosen = s.key;
  }

  $('.an-add').addEventListener('click', () => { add($('.an-add-brdf').value); changed(); });
  $('.an-clear').addEventListener('click', () => { series = []; chosen = null; changed(); });
  for (const b of el.querySelectorAll('.an-preset')) {
    b.addEventListener('click', () => {
      series = [];
      for (const p of PRESETS[b.dataset.preset]) add(p.brdf, p.params || {});
      chosen = series[0]?.key ?? null;
      changed();
    });
  }
  theta.addEventListener('input', () => {
    $('.an-theta-out').textContent = `${thetaI()}°`;
    albedo.marker(thetaI());
    draw('slice');
    update();
  });
  $('.an-plane').addEventListener('change', () => draw('polar'));
  $('.an-log').addEventListener('change', () => { draw('polar'); draw('slice'); });

  // The library (analysable files only: legacy ones are rendered, not analysed).
  on('library', ({ library }) => {
    const sel = $('.an-add-brdf');
    const keep = sel.value;
    sel.replaceChildren(...library.filter((b) => b.format === 'explorer' && !b.broken).map((b) => {
      const o = document.createElement('option');
      o.value = o.textContent = b.name;
      return o;
    }));
    if (keep) sel.value = keep;
    start();
  });

  // First showing: load three.js, and start with the selected object's BRDF and values.
  let loading = null;
  let started = false;
  function start() {
    if (!shown() || !state.library.length || !state.scene) return;
    if (!started) {
      started = true;
      const name = state.scene.objects?.[state.selected]?.brdf;
      if (name) { add(name); $('.an-add-brdf').value = name; }
      changed();
    }
    loading ||= import('../analysis-plots/lobe3d.js').then((m) => {
      lobe = m.lobeView($('.an-lobe'));
      draw('lobe');
    }).catch((e) => { $('.an-lobe').textContent = `3D view unavailable: ${e.message}`; });
    update();
  }
  on('tab', start);
  on('scene', () => { if (!started) start(); });
  window.addEventListener('resize', () => {
    if (!shown()) return;
    for (const kind of ['polar', 'slice']) draw(kind);
    albedo.resize();
    lobe?.resize();
  });
}
