// The browser checks, in order; each may rely on what the earlier ones set up in `env`
// (env.page, env.sid, ...). A check throws to fail. See run.mjs for how they are run.
import assert from 'node:assert/strict';
import { join } from 'node:path';

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function http(env, method, path, body) {
  const res = await fetch(env.server.url + path, {
    method,
    headers: body === undefined ? {} : { 'Content-Type': 'application/json' },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const text = await res.text();
  if (!res.ok) throw new Error(`${method} ${path}: ${res.status} ${text}`);
  return text ? JSON.parse(text) : null;
}

async function until(what, fn, timeout = 20000) {
  const end = Date.now() + timeout;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}`);
    await sleep(50);
  }
}

/** Opens the UI in a new tab, records console errors, waits for a non-blank frame. */
async function openTab(env, label) {
  const page = await env.context.newPage();
  page.errors = [];
  page.on('console', (m) => { if (m.type() === 'error') page.errors.push(`${label} console: ${m.text()}`); });
  page.on('pageerror', (e) => page.errors.push(`${label} page error: ${e.message}`));
  await page.goto(env.server.url + '/');
  // Navigation start is performance.now() == 0, so this is page load -> first frame on screen.
  const firstFrameMs = await env.waitForFrame(page, { minVariance: 20 });
  const sid = new URL(page.url()).searchParams.get('session');
  assert.match(sid || '', /^[0-9a-f]{16}$/, `URL carries ?session=<id>, got ${page.url()}`);
  return { page, sid, firstFrameMs };
}

// Analysis needs frames that stop changing: a low sample cap makes a session converge in a few
// passes, after which the stream sends nothing new until the scene changes. Set over the API,
// not the UI, which never sends `render` (so it does not undo it).
async function capSamples(env, sid) {
  await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { render: { max_samples: 16 } });
}

/** Waits until the session converged and the frame on screen is its final one. */
async function settle(env, page, sid) {
  await until('convergence', async () => (await http(env, 'GET', `/api/sessions/${sid}/stats`)).converged);
  let prev = await env.grab(page);
  return until('a stable frame', async () => {
    await sleep(150);
    const now = await env.grab(page);
    const same = now && prev && env.meanDiff(now, prev) === 0;
    prev = now;
    return same && now;
  });
}

const shot = (env, page, name) => page.screenshot({ path: join(env.artifacts, `${name}.png`) });
const compiles = async (env) => (await http(env, 'GET', '/api/health')).compiler.glsl_compiles;

/** Sets a parameter slider as a drag does (an `input` event) and times it to the new frame. */
async function moveSlider(env, page, sid, name, value) {
  const before = await settle(env, page, sid);
  const t0 = await page.evaluate(({ name, value }) => {
    const input = document.querySelector(`#params input[name="${name}"]`);
    input.value = String(value);
    const t = performance.now();
    input.dispatchEvent(new Event('input', { bubbles: true }));
    return t;
  }, { name, value });
  const t1 = await env.waitForFrame(page, { before, threshold: 0.5 });
  return t1 - t0;
}

export const checks = [
  ['page loads and shows a non-blank frame', async (env) => {
    env.fatal = true;
    const tab = await openTab(env, 'tab1');
    Object.assign(env, { page: tab.page, sid: tab.sid });
    console.log(`TIMING page load -> first frame: ${tab.firstFrameMs.toFixed(0)} ms`);
    const px = await env.grab(env.page);
    assert.ok(env.variance(px) > 20, 'the frame is not blank');
    assert.notEqual(env.sid, 'default');
    await shot(env, env.page, '01-loaded');
    await capSamples(env, env.sid);
    env.fatal = false;
  }],

  ['a syntax error gets a lint marker on its line; the fix brings a new frame', async (env) => {
    const { page, sid } = env;
    const source = (await http(env, 'GET', '/api/brdfs/ggx')).source;
    const line = source.split('\n').findIndex((l) => l.includes('float a2 = a * a;')) + 1;
    assert.ok(line > 0, 'ggx.brdf has the line this test edits');
    const before = await settle(env, page, sid);

    await page.click('.cm-content');
    await page.keyboard.press('Control+Home');
    for (let i = 1; i < line; ++i) await page.keyboard.press('ArrowDown');
    await page.keyboard.press('End');
    await page.keyboard.press('ArrowLeft');                 // before the ';'
    await page.keyboard.type(' * * 4.0');                   // a * a * * 4.0;  -> syntax error
    const marker = page.locator('.cm-gutter-lint .cm-lint-marker-error').first();
    await marker.waitFor({ timeout: 20000 });
    // The marker's gutter row lines up with the line-number gutter's row of the same line.
    const markedLine = await page.evaluate(() => {
      const m = document.querySelector('.cm-gutter-lint .cm-lint-marker-error').getBoundingClientRect();
      const rows = [...document.querySelectorAll('.cm-lineNumbers .cm-gutterElement')];
      const row = rows.find((r) => { const b = r.getBoundingClientRect(); return b.height && m.top >= b.top - 1 && m.top < b.bottom; });
      return row ? Number(row.textContent) : -1;
    });
    assert.equal(markedLine, line, 'the error marker sits on the edited line');
    const listed = await page.locator('#editor .diagnostics li').first().textContent();
    assert.match(listed, new RegExp(`^line ${line}:`), 'the message names the line');
    await shot(env, page, '02-syntax-error');

    await page.keyboard.press('ArrowLeft');
    await page.keyboard.press('ArrowLeft');
    await page.keyboard.press('ArrowLeft');
    await page.keyboard.press('ArrowLeft');                 // after the second '*'
    await page.keyboard.press('Backspace');                 // a * a *  4.0;  -> valid, different D
    await env.waitForFrame(page, { before, threshold: 0.5 });
    await until('the marker to go', async () => (await page.locator('.cm-lint-marker-error').count()) === 0);
    const scene = await http(env, 'GET', `/api/sessions/${sid}/scene`);
    assert.equal(scene.objects[0].brdf, `scratch-${sid}`, 'objects[0] uses the session scratch BRDF');
    const fixed = await settle(env, page, sid);
    assert.ok(env.meanDiff(before, fixed) > 0.5, 'the fixed BRDF renders differently');
    await shot(env, page, '03-fixed');
  }],

  ['a slider changes the frame without a recompile', async (env) => {
    const { page, sid } = env;
    const compilesBefore = await compiles(env);
    const times = [];
    for (const v of [0.9, 0.1, 0.6, 0.2, 0.8]) times.push(await moveSlider(env, page, sid, 'roughness', v));
    const scene = await http(env, 'GET', `/api/sessions/${sid}/scene`);
    assert.ok(Math.abs(scene.objects[0].params.roughness - 0.8) < 0.002, 'the slider PATCHed objects[0].params');
    assert.equal(await compiles(env), compilesBefore, 'no GLSL compile for a parameter change');
    const sorted = [...times].sort((a, b) => a - b);
    console.log(`TIMING slider -> updated frame: median ${sorted[2].toFixed(0)} ms, ` +
      `max ${sorted[4].toFixed(0)} ms (${times.map((t) => t.toFixed(0)).join(', ')})`);
    await shot(env, page, '04-slider');
  }],

  ['W moves the camera', async (env) => {
    const { page, sid } = env;
    const p0 = (await http(env, 'GET', `/api/sessions/${sid}/scene`)).camera.position;
    await page.locator('#viewer').focus();
    await page.keyboard.down('w');
    await sleep(400);
    await page.keyboard.up('w');
    await until('the camera to move', async () =>
      (await http(env, 'GET', `/api/sessions/${sid}/scene`)).camera.position[2] < p0[2] - 0.1);
    let last = null;
    const p1 = await until('the camera to stop', async () => {   // the last PATCH may still be in flight
      const p = (await http(env, 'GET', `/api/sessions/${sid}/scene`)).camera.position;
      const still = last && p[2] === last[2];
      last = p;
      await sleep(100);
      return still && p;
    });
    assert.ok(Math.abs(p1[0] - p0[0]) < 1e-6 && Math.abs(p1[1] - p0[1]) < 1e-6, 'W moves along -Z at yaw 0, pitch 0');
    const shown = Number(await page.locator('#camera input[name="pz"]').inputValue());
    assert.ok(Math.abs(shown - p1[2]) < 0.01, 'the camera panel shows the new position');
    await shot(env, page, '05-moved');
  }],

  ['two tabs get separate sessions; a change in one does not show in the other', async (env) => {
    const tab2 = await openTab(env, 'tab2');
    console.log(`TIMING page load -> first frame, second tab (ggx compiled already): ${tab2.firstFrameMs.toFixed(0)} ms`);
    console.log(`TIMING breakdown: ${await tab2.page.evaluate(() => performance.getEntriesByType('resource')
      .map((r) => `${r.name.replace(location.origin, '').slice(0, 40)} ${r.startTime.toFixed(0)}+${r.duration.toFixed(0)}`).join('; '))}`);
    env.page2 = tab2.page;
    assert.notEqual(tab2.sid, env.sid, 'each tab has its own session');
    await capSamples(env, tab2.sid);
    const frame2 = await settle(env, tab2.page, tab2.sid);
    const scene2 = await http(env, 'GET', `/api/sessions/${tab2.sid}/scene`);

    await moveSlider(env, env.page, env.sid, 'roughness', 0.05);
    await sleep(500);
    assert.equal(env.meanDiff(frame2, await env.grab(tab2.page)), 0, 'tab 2 shows the same frame');
    assert.deepEqual(await http(env, 'GET', `/api/sessions/${tab2.sid}/scene`), scene2, 'tab 2 scene unchanged');
    assert.equal(scene2.objects[0].brdf, 'ggx');
    await shot(env, tab2.page, '06-second-tab');

    // A reload keeps the session (its id is in the URL).
    await env.page.reload();
    await env.waitForFrame(env.page, { minVariance: 20 });
    assert.equal(new URL(env.page.url()).searchParams.get('session'), env.sid, 'a reload keeps the session');
  }],

  ['no console errors', async (env) => {
    // Chromium logs every 4xx answer to fetch as "Failed to load resource"; the 422 of the
    // syntax-error check is the API's expected answer to bad source, not a UI error.
    const expected = /Failed to load resource: .*status of 422/;
    const errors = env.context.pages().flatMap((p) => p.errors || []).filter((e) => !expected.test(e));
    assert.deepEqual(errors, []);
  }],
];
