// Browser checks of the Analysis tab and the side-by-side view, run by
// run.mjs after checks.mjs in a tab of their own. Screenshots: analysis-*.png, side-by-side*.png.
import assert from 'node:assert/strict';
import { createHash } from 'node:crypto';
import { http, until, sleep, openTab, capSamples, shot } from './checks.mjs';

const PLOTS = { polar: '#analysis .an-polar', lobe: '#analysis .an-lobe canvas', albedo: '#analysis .an-albedo canvas', slice: '#analysis .an-slice' };

/** SHA-1 of each plot's pixels as shown (an element screenshot: WebGL and 2D canvases alike). */
async function plotHashes(page) {
  const out = {};
  for (const [name, sel] of Object.entries(PLOTS)) {
    out[name] = createHash('sha1').update(await page.locator(sel).first().screenshot()).digest('hex');
  }
  return out;
}

/** Records the page's analysis requests (kind, body, answered) and the most in flight at once. */
function watchAnalysis(page) {
  const log = { calls: [], inFlight: 0, maxInFlight: 0 };
  const kindOf = (url) => (/\/api\/analysis\/(\w+)/.exec(url) || [])[1];
  page.on('request', (r) => {
    const kind = kindOf(r.url());
    if (!kind) return;
    log.calls.push({ kind, body: r.postDataJSON(), request: r, answered: false });
    log.maxInFlight = Math.max(log.maxInFlight, ++log.inFlight);
  });
  const done = (r, ok) => {
    if (!kindOf(r.url())) return;
    log.inFlight--;
    const call = log.calls.find((c) => c.request === r);
    if (call) Object.assign(call, { answered: ok, status: ok ? r.response().then((x) => x?.status()) : null });
  };
  page.on('requestfinished', (r) => done(r, true));
  page.on('requestfailed', (r) => done(r, false));
  return log;
}

/** The last answered call of `kind` that `test(body)` accepts. */
const answered = (log, kind, test = () => true) => log.calls.filter((c) => c.kind === kind && c.answered && test(c.body)).at(-1);

/** Waits until every plot shows an answer to a request that `test(kind, body)` accepts, and nothing is in flight. */
async function plotsFor(page, log, test, what) {
  await until(what, async () => ['polar', 'lobe', 'albedo', 'slice'].every((k) => answered(log, k, (b) => test(k, b))) && log.inFlight === 0, 60000);
  await sleep(300);   // the last answer drawn (uPlot is created after its module loads)
}

const names = (body) => body.series.map((s) => s.brdf).join(',');

export const analysisChecks = [
  ['the Analysis tab overlays the D terms, and moving theta_i changes every plot', async (env) => {
    const { page, sid } = await openTab(env, 'analysis');
    Object.assign(env, { analysisPage: page, analysisSid: sid });
    page.consoleAt = page.errors.length;
    page.on('console', (m) => {   // where a failed load came from (Chromium's text does not say)
      if (m.type() === 'error') page.errors[page.errors.length - 1] += ` @ ${m.location().url}`;
    });
    await capSamples(env, sid);
    const log = watchAnalysis(page);
    env.analysisLog = log;
    await page.click('.tabs [data-tab="tab-analysis"]');
    // It starts with the session's object: one ggx series, all four plots.
    await plotsFor(page, log, (k, b) => names(b) === 'ggx', 'the first plots (ggx)');
    assert.equal(await page.locator('#analysis .an-legend li').count(), 1);

    await page.click('#analysis .an-preset[data-preset="D"]');
    await plotsFor(page, log, (k, b) => names(b) === (k === 'slice' ? 'D_beckmann' : 'D_beckmann,D_ggx,D_blinn'), 'the D terms plotted');
    const legend = await page.locator('#analysis .an-legend li .an-pick').allTextContents();
    assert.deepEqual(legend, ['D_beckmann', 'D_ggx', 'D_blinn'], 'the legend lists the three D terms');
    const polar = answered(log, 'polar', (b) => b.series.length === 3).body;
    assert.deepEqual(polar.series.map((s) => s.params), [{ m: 0.3 }, { alpha: 0.3 }, { n: 20.2 }], 'Beckmann m 0.3, GGX alpha 0.3, Blinn n = 2/m^2 - 2');
    assert.equal(await page.locator(PLOTS.polar).getAttribute('data-curves'), '3', 'three curves on the polar plot');
    assert.equal(await page.locator('#analysis .an-lobe').getAttribute('data-series'), '3', 'three lobes');
    assert.equal(await page.locator('#analysis .an-albedo').getAttribute('data-series'), '3', 'three albedo curves');
    assert.equal(await page.locator(PLOTS.slice).getAttribute('data-drawn'), '1', 'the slice heat map is drawn');
    const albedo = await answered(log, 'albedo', (b) => b.series.length === 3).request.response().then((r) => r.json());
    assert.ok(albedo.series.every((s) => s.std_error.every((e) => e.every((x) => x >= 0))), 'albedo answers carry standard errors');
    const before = await plotHashes(page);
    await shot(env, page, 'analysis-d-terms');

    // theta_i 30 -> 60: the polar plot and the lobe are fetched again; albedo and slice move their marks.
    await page.evaluate(() => {
      const input = document.querySelector('#analysis .an-theta');
      input.value = '60';
      input.dispatchEvent(new Event('input', { bubbles: true }));
    });
    await plotsFor(page, log, (k, b) => (k === 'polar' || k === 'lobe' ? b.theta_i === 60 && b.series.length === 3 : b.series[0].brdf === 'D_beckmann'), 'the plots at theta_i 60');
    await until('the lobe drawn for 60', async () => (await page.locator('#analysis .an-lobe').getAttribute('data-theta-i')) === '60');
    const after = await plotHashes(page);
    for (const k of Object.keys(PLOTS)) assert.notEqual(after[k], before[k], `the ${k} plot changed with theta_i`);
    const polar60 = await answered(log, 'polar', (b) => b.theta_i === 60).request.response().then((r) => r.json());
    const polar30 = await answered(log, 'polar', (b) => b.theta_i === 30 && b.series.length === 3).request.response().then((r) => r.json());
    assert.notDeepEqual(polar60.series[0].values.incidence, polar30.series[0].values.incidence, 'the polar data changed');
    await shot(env, page, 'analysis-theta-60');
  }],

  ['analysis sliders update live, one request in flight, the latest value winning', async (env) => {
    const page = env.analysisPage;
    const log = env.analysisLog;
    await page.click('#analysis .an-legend li:nth-child(2) .an-pick');   // D_ggx: its sliders and its slice
    await page.locator('#analysis .an-params input[name="alpha"]').waitFor();
    const n0 = log.calls.length;
    // A drag: 20 values within a few milliseconds.
    await page.evaluate(() => {
      const input = document.querySelector('#analysis .an-params input[name="alpha"]');
      for (let i = 1; i <= 20; ++i) {
        input.value = String(0.3 + i * 0.01);
        input.dispatchEvent(new Event('input', { bubbles: true }));
      }
    });
    // (a range input snaps to its step: (max - min) / 1000)
    const last = (b) => Math.abs(b.series[b.series.length === 1 ? 0 : 1].params.alpha - 0.5) < 0.002;
    await plotsFor(page, log, (k, b) => (k === 'slice' ? b.series[0].brdf === 'D_ggx' : true) && last(b), 'the plots for alpha 0.5');
    const polars = log.calls.slice(n0).filter((c) => c.kind === 'polar');
    assert.ok(polars.length < 20, `coalesced: ${polars.length} polar requests for 20 slider values`);
    assert.ok(log.maxInFlight <= 1, `at most one analysis request in flight (saw ${log.maxInFlight})`);

    // The G and F presets plot too (names and parameters as in shaders/brdfs).
    await page.click('#analysis .an-preset[data-preset="G"]');
    await plotsFor(page, log, (k, b) => k === 'slice' || b.series.length === 5, 'the G terms plotted');
    await page.click('#analysis .an-preset[data-preset="F"]');
    await plotsFor(page, log, (k, b) => k === 'slice' || names(b) === 'F_schlick,F_dielectric,F_conductor', 'the F terms plotted');
    for (const c of log.calls) assert.equal(await c.status, 200, `${c.kind} ${JSON.stringify(c.body).slice(0, 120)} answered ${await c.status}`);
    assert.doesNotMatch(await page.locator('#analysis .an-status').textContent(), /:/, 'no error in the status line');
    await shot(env, page, 'analysis-f-terms');
  }],

  ['side by side: B streams beside A, mirrors its camera, and the difference shows with its colour bar and rel. RMS', async (env) => {
    const page = env.analysisPage;
    const sid = env.analysisSid;
    await page.click('.tabs [data-tab="tab-compare"]');
    await page.selectOption('#compare .sbs-brdf', 'lambert');
    await page.click('#compare .sbs-open');
    const bid = await until('B created', () => page.locator('#compare').getAttribute('data-session'));
    assert.match(bid, /^[0-9a-f]{16}$/);
    assert.notEqual(bid, sid);
    const sceneA = await http(env, 'GET', `/api/sessions/${sid}/scene`);
    const sceneB = await http(env, 'GET', `/api/sessions/${bid}/scene`);
    assert.equal(sceneB.objects[0].brdf, 'lambert', 'B renders the chosen BRDF');
    for (const k of ['camera', 'environment', 'render']) assert.deepEqual(sceneB[k], sceneA[k], `B has A's ${k}`);

    // B's pane shows frames of its stream (same origin: its pixels are readable).
    const bPixels = () => page.evaluate(() => {
      const img = document.querySelector('#compare .sbs-b');
      if (!img.complete || !img.naturalWidth) return null;
      const c = document.createElement('canvas');
      c.width = c.height = 32;
      const g = c.getContext('2d', { willReadFrequently: true });
      g.drawImage(img, 0, 0, 32, 32);
      return [...g.getImageData(0, 0, 32, 32).data];
    });
    const px = await until('a frame in the B pane', bPixels);
    assert.ok(env.variance(px) > 20, 'B frame is not blank');
    assert.ok((await http(env, 'GET', `/api/sessions/${bid}`)).stream_clients >= 1, 'B is streamed');
    await until('the difference image', () => page.evaluate(() => document.querySelector('#compare .sbs-diff').naturalWidth > 0));
    const rms = await until('the rel. RMS with its error bar', async () => {
      const t = await page.locator('#compare .sbs-rms').textContent();
      return /relative RMS difference \d[\d.]*% ± \d[\d.]*%/.test(t) && t;
    });
    assert.ok(parseFloat(/difference ([\d.]+)%/.exec(rms)[1]) > 1, `ggx and lambert differ: ${rms}`);
    const bar = await page.locator('#compare .sbs-bar').boundingBox();
    assert.ok(bar && bar.width > 100, 'the colour bar is drawn');

    // A camera change of A is mirrored into B.
    await page.fill('#camera input[name="fov"]', '55');
    await page.press('#camera input[name="fov"]', 'Enter');
    await until('B to follow the camera', async () => (await http(env, 'GET', `/api/sessions/${bid}/scene`)).camera.fov === 55);
    // Both capped at 16 samples: the last difference is of both final frames.
    await until('the difference of both final frames', async () => /\d% ± .*A 16 spp, B 16 spp/.test(await page.locator('#compare .sbs-rms').textContent()));
    await shot(env, page, 'side-by-side');

    // Close deletes B; so does leaving the page.
    await page.click('#compare .sbs-close');
    await until('B deleted on close', async () => (await fetch(`${env.server.url}/api/sessions/${bid}`)).status === 404);
    await page.click('#compare .sbs-open');
    const bid2 = await until('B again', () => page.locator('#compare').getAttribute('data-session'));
    await until('B2 streamed', async () => (await http(env, 'GET', `/api/sessions/${bid2}`)).stream_clients >= 1);
    await page.goto('about:blank');
    await until('B deleted when the page goes', async () => (await fetch(`${env.server.url}/api/sessions/${bid2}`)).status === 404);
  }],

  ['no console errors in the analysis tab', async (env) => {
    // A difference asked for in the moment after a camera change, before a view has its first
    // error estimate, is the API's 400 (docs/api.md): expected, the UI waits and asks again.
    const errors = env.analysisPage.errors.slice(env.analysisPage.consoleAt)
      .filter((e) => !/status of 400 .*\/difference\?/.test(e));
    assert.deepEqual(errors, []);
  }],
];
