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

/** draw(kind): one plot from the answer it has (none: empty). */
function makeDraw(a) {
  const { $ } = a;
  return function draw(kind) {
    const got = a.answers[kind];
    const log = $('.an-log').checked;
    if (kind === 'polar') drawPolar($('.an-polar'), got?.answer, { plane: $('.an-plane').value, log, thetaI: got?.answer?.theta_i ?? a.thetaI(), colors: got?.colors || [] });
    if (kind === 'slice') {
      drawSlice($('.an-slice'), got?.answer, { log, thetaI: a.thetaI() });
      $('.an-slice-label').textContent = got?.answer?.series?.[0]?.label || '';
    }
    if (kind === 'albedo') a.albedo.set(got?.answer, got?.colors || []).then(() => a.albedo.marker(a.thetaI()));
    if (kind === 'lobe' && a.lobe) {
      const top = a.lobe.set(got?.answer, got?.colors || []);
      $('.an-lobe').dataset.thetaI = String(got?.answer?.theta_i ?? '');
      $('.an-lobe-max').textContent = got?.answer ? `(largest f ${sig(top)})` : '';
    }
  };
}

/** update(): asks for the plots whose request changed, one request at a time. */
function makeUpdate(el, a) {
  const sent = {};     // kind -> the body of the answer shown
  let retry = 0;
  let latest = null;   // the newest snapshot asked for
  const snapshot = () => ({ series: a.series.map((s) => ({ ...s })), thetaI: a.thetaI(), chosen: a.chosen });
  const figure = (kind) => el.querySelector(`.an-${kind}`).closest('figure');
  const dim = (kind) => figure(kind).classList.toggle('stale', !!latest?.series.length && sent[kind] !== requestOf(kind, latest).key);

  // One request at a time; a newer state waiting makes the rest of this round stale.
  const refresh = coalesce(async (snap) => {
    const times = [];
    for (const kind of KINDS) {
      if (refresh.waiting()) return;
      if (!snap.series.length) { a.answers[kind] = null; delete sent[kind]; a.draw(kind); continue; }
      const { wire, key } = requestOf(kind, snap);
      if (sent[kind] === key) continue;
      try {
        const answer = await api.analysis(kind, wire);
        a.answers[kind] = { answer, colors: kind === 'slice' ? [requestOf(kind, snap).color] : snap.series.map((s) => s.color) };
        sent[kind] = key;
        times.push(`${kind} ${Math.round(answer.ms)} ms`);
        if (kind === 'polar') a.showNotes(answer);
        a.draw(kind);
        dim(kind);
      } catch (e) {
        a.status.textContent = `${kind}: ${e.message}`;
        if (e.status === 503) { clearTimeout(retry); retry = setTimeout(update, RETRY_MS); }
        return;
      }
    }
    if (times.length) a.status.textContent = times.join(' · ');
  });
  // A plot whose request changed is dimmed until its answer is drawn.
  function update() {
    if (!a.shown()) return;
    latest = snapshot();
    KINDS.forEach(dim);
    refresh(latest);
  }
  return update;
}

/** The legend: one entry a series (choose it: its sliders and its slice; remove it). */
function makeLegend(a) {
  const { $ } = a;
  const legend = $('.an-legend');
  function showLegend() {
    legend.replaceChildren(...a.series.map((s) => {
      const li = document.createElement('li');
      li.className = s.key === a.chosen ? 'chosen' : '';
      li.dataset.key = String(s.key);
      const pick = document.createElement('button');
      pick.type = 'button';
      pick.className = 'an-pick';
      const swatch = document.createElement('i');
      swatch.className = 'swatch';
      swatch.style.background = s.color;
      pick.append(swatch, s.label);   // the label (a BRDF name) as text
      pick.title = 'show its parameters and its slice';
      pick.addEventListener('click', () => { a.chosen = s.key; showLegend(); a.showParams(); a.update(); });
      const remove = document.createElement('button');
      remove.type = 'button';
      remove.className = 'an-remove';
      remove.textContent = '×';
      remove.setAttribute('aria-label', `remove ${s.label}`);
      remove.addEventListener('click', () => {
        a.series = a.series.filter((x) => x !== s);
        if (a.chosen === s.key) a.chosen = a.series[0]?.key ?? null;
        a.changed();
      });
      const notes = document.createElement('span');
      notes.className = 'an-notes';
      notes.textContent = (s.notes || []).join('; ');
      li.append(pick, remove, notes);
      return li;
    }));
    legend.dataset.count = String(a.series.length);
    $('.an-add').disabled = a.series.length >= MAX_SERIES;
  }
  return showLegend;
}

/** The series: add, clear, the presets' sets, and the chosen one's parameter sliders. */
function mountSeries(a) {
  const { $ } = a;
  // What the server clamped (values outside a BRDF's range), beside the series it concerns.
  a.showNotes = (answer) => {
    answer.series.forEach((x, i) => { if (a.series[i]?.label === x.label) a.series[i].notes = x.notes; });
    a.showLegend();
  };
  a.showParams = () => {
    const s = a.series.find((x) => x.key === a.chosen);
    const host = $('.an-params');
    if (!s) { host.replaceChildren(); return; }
    paramControls(host, s.decls, s.params, (values) => { s.params = values; a.update(); });
  };
  a.changed = () => {
    a.showLegend();
    a.showParams();
    a.update();
  };
  a.add = (name, params) => {
    if (a.series.length >= MAX_SERIES) return;
    if (!state.library.some((b) => b.name === name)) { a.status.textContent = `${name} is not in the library`; return; }
    const s = makeSeries(name, { library: state.library, object: state.scene?.objects?.[state.selected], taken: a.series, params });
    a.series.push(s);
    a.chosen = s.key;
  };
  $('.an-add').addEventListener('click', () => { a.add($('.an-add-brdf').value); a.changed(); });
  $('.an-clear').addEventListener('click', () => { a.series = []; a.chosen = null; a.changed(); });
  for (const b of a.el.querySelectorAll('.an-preset')) {
    b.addEventListener('click', () => {
      a.series = [];
      for (const p of PRESETS[b.dataset.preset]) a.add(p.brdf, p.params || {});
      a.chosen = a.series[0]?.key ?? null;
      a.changed();
    });
  }
}

/** θi, the plane and the log scale; the list of BRDFs to add. */
function mountControls(a) {
  const { $ } = a;
  a.theta.addEventListener('input', () => {
    $('.an-theta-out').textContent = `${a.thetaI()}°`;
    a.albedo.marker(a.thetaI());
    a.draw('slice');
    a.update();
  });
  $('.an-plane').addEventListener('change', () => a.draw('polar'));
  $('.an-log').addEventListener('change', () => { a.draw('polar'); a.draw('slice'); });
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
    a.start();
  });
}

export function mountAnalysis(el) {
  el.innerHTML = MARKUP;
  const $ = (c) => el.querySelector(c);
  // What the sub-views share: the series, the chosen one, the answers drawn.
  const a = {
    el,
    $,
    theta: $('.an-theta'),
    status: $('.an-status'),
    albedo: albedoPlot($('.an-albedo')),
    lobe: null,       // three.js loads with the tab's first showing
    series: [],
    chosen: null,     // key of the series whose sliders and slice are shown
    answers: {},      // kind -> {answer, colors}
    shown: () => !el.closest('.tab-page')?.hidden,
  };
  a.thetaI = () => Number(a.theta.value);
  a.draw = makeDraw(a);
  a.update = makeUpdate(el, a);
  a.showLegend = makeLegend(a);
  mountSeries(a);

  // First showing: load three.js, and start with the selected object's BRDF and values.
  let loading = null;
  let started = false;
  a.start = () => {
    if (!a.shown() || !state.library.length || !state.scene) return;
    if (!started) {
      started = true;
      const name = state.scene.objects?.[state.selected]?.brdf;
      if (name) { a.add(name); $('.an-add-brdf').value = name; }
      a.changed();
    }
    loading ||= import('../analysis-plots/lobe3d.js').then((m) => {
      a.lobe = m.lobeView($('.an-lobe'));
      a.draw('lobe');
    }).catch((e) => { $('.an-lobe').textContent = `3D view unavailable: ${e.message}`; });
    a.update();
  };
  mountControls(a);
  on('tab', a.start);
  on('scene', () => { if (!started) a.start(); });
  window.addEventListener('resize', () => {
    if (!a.shown()) return;
    for (const kind of ['polar', 'slice']) a.draw(kind);
    a.albedo.resize();
    a.lobe?.resize();
  });
}
