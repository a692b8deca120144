// The browser checks, in order; each may rely on what the earlier ones set up in `env`
// (env.page, env.sid, ...). A check throws to fail. See run.mjs for how they are run. The
// helpers marked `export` serve the other check modules too (layout.mjs).
import assert from 'node:assert/strict';
import { join } from 'node:path';

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// JSON in and out; a `type` sends `body` as it is (a .brdf text).
export async function http(env, method, path, body, type) {
  const res = await fetch(env.server.url + path, {
    method,
    headers: body === undefined ? {} : { 'Content-Type': type || 'application/json' },
    body: body === undefined ? undefined : type ? body : JSON.stringify(body),
  });
  const text = await res.text();
  if (!res.ok) throw new Error(`${method} ${path}: ${res.status} ${text}`);
  return text ? JSON.parse(text) : null;
}

export async function until(what, fn, timeout = 20000) {
  const end = Date.now() + timeout;
  for (;;) {
    const v = await fn();
    if (v) return v;
    if (Date.now() > end) throw new Error(`timed out waiting for ${what}`);
    await sleep(50);
  }
}

/** Opens the UI in a new tab, records console errors, waits for a non-blank frame. */
export async function openTab(env, label) {
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
export async function capSamples(env, sid) {
  await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { render: { max_samples: 16 } });
}

/** Waits until the session is done (max_samples reached) and the frame on screen is its final one. */
export async function settle(env, page, sid) {
  await until('rendering done', async () => (await http(env, 'GET', `/api/sessions/${sid}/stats`)).done);
  let prev = await env.grab(page);
  return until('a stable frame', async () => {
    await sleep(150);
    const now = await env.grab(page);
    const same = now && prev && env.meanDiff(now, prev) === 0;
    prev = now;
    return same && now;
  });
}

/** A world point in normalized device coordinates of the scene's camera (renderer convention:
 *  yaw about +Y with 0 looking down -Z, pitch up; fov vertical). z: depth along the view. */
export function project(camera, point, aspect) {
  const y = (camera.yaw * Math.PI) / 180, p = (camera.pitch * Math.PI) / 180;
  const f = [-Math.sin(y) * Math.cos(p), Math.sin(p), -Math.cos(y) * Math.cos(p)];
  const r = [Math.cos(y), 0, -Math.sin(y)];
  const u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]];
  const d = point.map((v, i) => v - camera.position[i]);
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const z = dot(d, f), t = Math.tan((camera.fov * Math.PI) / 360);
  return { x: dot(d, r) / (z * t * aspect), y: dot(d, u) / (z * t), z };
}

export const shot = (env, page, name) => page.screenshot({ path: join(env.artifacts, `${name}.png`) });
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
    const line = source.split('\n').findIndex((l) => l.includes('float NoL = dot(N, L);')) + 1;
    assert.ok(line > 0, 'ggx.brdf has the line this test edits');
    const before = await settle(env, page, sid);

    await page.click('.cm-content');
    await page.keyboard.press('Control+Home');
    for (let i = 1; i < line; ++i) await page.keyboard.press('ArrowDown');
    await page.keyboard.press('End');
    await page.keyboard.press('ArrowLeft');                 // before the ';'
    await page.keyboard.type(' * * 4.0');                   // dot(N, L) * * 4.0;  -> syntax error
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
    await page.keyboard.press('Backspace');                 // dot(N, L) *  4.0;  -> valid, a different V term
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
    // On a loaded machine the last PATCH can still be in flight when two reads agree: wait
    // until the server and the panel agree.
    await until('the camera panel to show the new position', async () => {
      const p = (await http(env, 'GET', `/api/sessions/${sid}/scene`)).camera.position;
      const shown = Number(await page.locator('#camera input[name="pz"]').inputValue());
      return Math.abs(shown - p[2]) < 0.01;
    }, 5000);
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

  ['the test window runs a batch: progress reaches 1, results appear, the view keeps rendering', async (env) => {
    const { page, sid } = env;
    // A file that claims reciprocity it does not have: its row must highlight that claim.
    const liar = 'analytic\n# claims: reciprocity, non-negativity\n::begin parameters\nfloat k 0 1 0.5\n' +
      '::end parameters\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) {\n' +
      '  return vec3(k + max(dot(N, V), 0.0)) / 3.14159265;\n}\n::end shader\n';
    await http(env, 'PUT', '/api/brdfs/web_claims_liar', liar, 'text/plain');
    await page.reload();
    await env.waitForFrame(page, { minVariance: 20 });
    const names = ['lambert', 'phong', 'ward', 'web_claims_liar'];
    // Uncapped, so the session renders (and streams) new passes for the whole job.
    await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { render: { max_samples: 1048576 } });
    await page.bringToFront();   // a background tab's animation frames are throttled
    await page.click('.tabs [data-tab="tab-test"]');
    for (const n of names) await page.check(`#tests .test-names input[value="${n}"]`);
    // In the page: count distinct frames on screen each animation frame from the click until
    // the progress bar is full.
    await page.evaluate(() => {
      const img = document.querySelector('#viewer img');
      const bar = document.querySelector('#tests .test-progress');
      const c = document.createElement('canvas');
      c.width = c.height = 32;
      const g = c.getContext('2d', { willReadFrequently: true });
      const sig = () => { g.drawImage(img, 0, 0, 32, 32); return g.getImageData(0, 0, 32, 32).data.join(','); };
      window.__job = { frames: 0, start: performance.now(), end: 0, progress: [] };
      let last = sig();
      const tick = () => {
        const s = sig();
        if (s !== last) { window.__job.frames++; last = s; }
        const p = Number(bar.value);
        if (window.__job.progress.at(-1) !== p) window.__job.progress.push(p);
        if (p >= 1) { window.__job.end = performance.now(); return; }
        requestAnimationFrame(tick);
      };
      document.querySelector('#tests .test-run').click();
      requestAnimationFrame(tick);
    });
    await until('the progress bar to reach 1', () => page.evaluate(() => window.__job.end > 0), 60000);
    const job = await page.evaluate(() => window.__job);
    const rows = await page.locator('#tests .test-results tbody tr').allTextContents();
    assert.equal(rows.length, 4, 'one result row per BRDF');
    for (const [i, n] of names.entries()) assert.ok(rows[i].startsWith(n), `row ${i} is ${n}: ${rows[i]}`);
    const cells = await page.locator('#tests .test-results tbody tr:first-child td').allTextContents();
    assert.equal(cells[1], 'yes', 'lambert passes');
    assert.ok(Number.isFinite(parseFloat(cells[3])), `compile ms shown: ${cells[3]}`);
    assert.match(await page.locator('#tests .test-status').textContent(), /^done: 4\/4/);
    // Claims: lambert holds all three; phong claims only non-negativity (the rest reported,
    // greyed); the liar's reciprocity is highlighted as violated, and only that.
    const chips = (row) => page.locator(`#tests .test-results tbody tr:nth-child(${row}) .claim`).evaluateAll(
      (els) => els.map((e) => `${e.dataset.claim}:${e.className.replace('claim ', '')}`));
    assert.deepEqual(await chips(1), ['reciprocity:holds', 'energy-conservation:holds', 'non-negativity:holds']);
    assert.deepEqual(await chips(2), ['reciprocity:unclaimed', 'energy-conservation:unclaimed', 'non-negativity:holds']);
    assert.deepEqual(await chips(4), ['reciprocity:violated', 'energy-conservation:unclaimed', 'non-negativity:holds']);
    const liarCells = await page.locator('#tests .test-results tbody tr:nth-child(4) td').allTextContents();
    assert.equal(liarCells[1], 'NO', 'a violated claim fails the BRDF');
    const red = await page.locator('#tests .test-results tbody tr:nth-child(4) .claim.violated')
      .evaluate((e) => getComputedStyle(e).backgroundColor);
    assert.equal(red, 'rgb(187, 0, 0)', 'the violated claim is highlighted');

    assert.match(await page.locator('#tests .test-log').textContent(), /^lambert:/, 'the first log is shown');
    await page.locator('#tests .test-results tbody tr:nth-child(4) button').click();
    assert.match(await page.locator('#tests .test-log').textContent(), /check: claim 'reciprocity' violated: .*at V \(theta/,
      'the log names the worst case');
    console.log(`TIMING test window: 3 BRDFs in ${(job.end - job.start).toFixed(0)} ms, ` +
      `${job.frames} new frames on screen meanwhile, progress ${job.progress.join(' -> ')}`);
    assert.ok(job.frames >= 2, `the stream kept delivering frames during the job (${job.frames})`);
    await shot(env, page, '07-test-window');
    await http(env, 'DELETE', '/api/brdfs/web_claims_liar');
    await page.click('.tabs [data-tab="tab-editor"]');
    await capSamples(env, sid);
  }],

  ['the frame saver downloads PNG, PFM and EXR', async (env) => {
    const { page, sid } = env;
    for (const [fmt, magic] of [['png', '\x89PNG'], ['pfm', 'PF'], ['exr', 'v/1\x01']]) {
      const href = await page.locator(`#frame-saver .save-${fmt}`).getAttribute('href');
      assert.ok(href.includes(`/api/sessions/${sid}/frame`) && href.includes(`format=${fmt}`) && href.includes('download=1'), href);
      const got = await page.evaluate(async (href) => {
        const r = await fetch(href);
        const b = new Uint8Array(await r.arrayBuffer());
        return { status: r.status, cd: r.headers.get('Content-Disposition'), head: String.fromCharCode(...b.slice(0, 4)) };
      }, href);
      assert.equal(got.status, 200);
      assert.match(got.cd || '', new RegExp(`attachment; filename="${sid}-\\d+spp\\.${fmt}"`));
      assert.ok(got.head.startsWith(magic), `${fmt} file starts with its magic (${JSON.stringify(got.head)})`);
    }
  }],

  ['Save as stores a named BRDF; presets save and load; a parameter resets alone', async (env) => {
    const { page, sid } = env;
    await page.bringToFront();
    page.once('dialog', (d) => d.accept('ui_saved'));
    await page.click('#library .lib-saveas');
    await until('the scene to use ui_saved', async () =>
      (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].brdf === 'ui_saved');
    const saved = await http(env, 'GET', '/api/brdfs/ui_saved');
    assert.equal(saved.builtin, false);
    await until('the library to list it', async () => (await page.locator('#library .library-list').inputValue()) === 'ui_saved');
    assert.equal(await page.locator('#library .lib-delete').isDisabled(), false, 'a user BRDF can be deleted');

    await moveSlider(env, page, sid, 'roughness', 0.7);
    page.once('dialog', (d) => d.accept('rough07'));
    await page.click('#params .preset-save');
    await until('the preset to be stored', async () =>
      (await http(env, 'GET', '/api/brdfs/ui_saved/presets')).includes('rough07'));
    assert.ok(Math.abs((await http(env, 'GET', '/api/brdfs/ui_saved/presets/rough07')).roughness - 0.7) < 0.002);

    const decl = saved.params.find((p) => p.name === 'roughness');
    // Found by its accessible name, as a screen reader announces it (the glyph alone is none).
    await page.getByRole('button', { name: 'reset roughness to its default', exact: true }).click();
    await until('roughness back to its default', async () =>
      Math.abs((await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].params.roughness - decl.default) < 1e-6);
    await page.selectOption('#params .preset-list', 'rough07');
    await page.click('#params .preset-load');
    await until('the preset applied', async () =>
      Math.abs((await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].params.roughness - 0.7) < 0.002);
    await shot(env, page, '08-saved-preset');
  }],

  ['New, the unsaved-changes warning, Revert and Delete in the library', async (env) => {
    const { page, sid } = env;
    const scratch = `scratch-${sid}`;
    // CodeMirror keeps the whole text in its state (the DOM holds only the lines in view).
    const editorText = () => page.evaluate(() => {
      const content = document.querySelector('.cm-content');
      const view = content.cmTile?.root?.view ?? content.cmView?.view;   // EditorView.findFromDOM, from outside the bundle
      return view.state.doc.toString();
    });
    const saved = (await http(env, 'GET', '/api/brdfs/ui_saved')).source;
    assert.equal(await editorText(), saved, 'the editor holds ui_saved (from Save as)');
    // An edit at the end of the text: unsaved, and shown as such.
    await page.click('.cm-content');
    await page.keyboard.press('Control+End');
    await page.keyboard.type('\n// an edit');
    await until('the unsaved marker', async () => (await page.locator('#library .library-state').textContent()).includes('unsaved'));

    // New with unsaved text asks first; dismissing keeps the text.
    const dialogs = [];
    const answer = (accept) => page.once('dialog', (d) => { dialogs.push(d.message()); return accept ? d.accept() : d.dismiss(); });
    answer(false);
    await page.click('#library .lib-new');
    await until('the discard question', async () => dialogs.length === 1);
    assert.match(dialogs[0], /unsaved changes/);
    assert.ok((await editorText()).endsWith('// an edit'), 'dismissing keeps the edited text');

    // Revert (confirmed) brings back the stored text.
    answer(true);
    await page.click('#library .lib-revert');
    await until('the saved text back', async () => (await editorText()) === saved);
    assert.match(dialogs[1], /Revert/);

    // New: the template, compiled into this tab's scratch BRDF, which the object now renders.
    await page.click('#library .lib-new');
    await until('the template', async () => (await editorText()).startsWith('analytic'));
    assert.equal(dialogs.length, 2, 'nothing to discard after Revert: no question');
    await until('the object to render the template', async () =>
      (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].brdf === scratch);

    // Open ui_saved again, then Delete it (confirmed): gone from the server and the list, and
    // the object keeps rendering its text as the scratch copy.
    await page.selectOption('#library .library-list', 'ui_saved');
    await until('ui_saved in use', async () => (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].brdf === 'ui_saved');
    answer(true);
    await page.click('#library .lib-delete');
    await until('ui_saved deleted', async () => (await fetch(`${env.server.url}/api/brdfs/ui_saved`)).status === 404);
    assert.match(dialogs[2], /Delete "ui_saved"/);
    // The page saves the scratch copy after the DELETE answers: wait for it, then check both.
    await until('the scratch copy to hold the deleted text', async () =>
      (await http(env, 'GET', `/api/brdfs/${scratch}`)).source === saved);
    assert.equal((await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].brdf, scratch);
    assert.equal((await http(env, 'GET', `/api/brdfs/${scratch}`)).source, saved, 'the scratch copy holds the deleted text');
    await until('the list to drop it', async () =>
      !(await page.locator('#library .library-list option').allTextContents()).some((t) => t.startsWith('ui_saved')));
    await shot(env, page, '09-library');
  }],

  ['the objects panel adds and removes objects (one always stays)', async (env) => {
    const { page, sid } = env;
    await page.click('.tabs [data-tab="tab-objects"]');
    assert.equal(await page.locator('#objects .obj-remove').isDisabled(), true, 'the only object cannot be removed');
    await page.click('#objects .obj-add');
    const scene = await until('two objects', async () => {
      const sc = await http(env, 'GET', `/api/sessions/${sid}/scene`);
      return sc.objects.length === 2 && sc;
    });
    // Both objects' centres project inside the image (the camera backed off if it had to).
    for (const o of scene.objects) {
      const ndc = project(scene.camera, o.translate, scene.render.width / scene.render.height);
      assert.ok(ndc.z > 0 && Math.abs(ndc.x) < 1 && Math.abs(ndc.y) < 1, `object at ${o.translate} is in view (${JSON.stringify(ndc)})`);
    }
    await page.selectOption('#objects .obj-mesh', 'cube');
    await until('the second object to be a cube', async () =>
      (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[1].mesh === 'cube');
    await shot(env, page, '10-objects');
    await page.click('#objects .obj-remove');
    await until('one object', async () => (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects.length === 1);
    assert.equal(await page.locator('#objects .obj-remove').isDisabled(), true);
    await page.click('.tabs [data-tab="tab-editor"]');
  }],

  ['the objects panel uploads a mesh and a texture, and the frame shows them', async (env) => {
    const { page, sid } = env;
    await page.click('.tabs [data-tab="tab-objects"]');
    const before = await settle(env, page, sid);
    // A tetrahedron (no normals, no UVs: the server makes them).
    const obj = 'v 0 1 0\nv -1 -0.6 0.8\nv 1 -0.6 0.8\nv 0 -0.6 -1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n';
    await page.setInputFiles('#objects .obj-mesh-upload', { name: 'tetra.obj', mimeType: 'text/plain', buffer: Buffer.from(obj) });
    const mesh = await until('the object to use the uploaded mesh', async () => {
      const m = (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].mesh;
      return m !== 'sphere' && m;
    });
    const listed = await http(env, 'GET', '/api/assets?kind=mesh');
    assert.ok(listed.some((a) => a.id === mesh && a.name === 'tetra.obj'), `the upload is listed as ${mesh}`);
    await env.waitForFrame(page, { before, threshold: 0.5 });

    // A texture: a PNG of part of the page, bound to the object's first slot.
    const png = await page.screenshot({ clip: { x: 0, y: 0, width: 64, height: 64 } });
    await page.setInputFiles('#objects .obj-tex-upload', { name: 'patch.png', mimeType: 'image/png', buffer: png });
    const texture = await until('the texture listed', async () =>
      (await http(env, 'GET', '/api/assets?kind=texture')).find((a) => a.name === 'patch.png'));
    await until('the texture bound to the first slot', async () => {
      const t = (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].textures || [];
      return t.length === 1 && (typeof t[0] === 'string' ? t[0] : t[0].name) === texture.id;
    });
    assert.equal(await page.locator('#objects .obj-status.error').count(), 0, 'no error shown');
    await shot(env, page, '11-uploads');
    // Back to the sphere for the checks after this one.
    await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { objects: [{ mesh: 'sphere', brdf: (await http(env, 'GET', `/api/sessions/${sid}/scene`)).objects[0].brdf }] });
    await page.click('.tabs [data-tab="tab-editor"]');
  }],

  ['the environment panel chooses or uploads an environment, sets intensity, rotation and visibility', async (env) => {
    const { page, sid } = env;
    await page.click('.tabs [data-tab="tab-environment"]');
    const envNow = async () => (await http(env, 'GET', `/api/sessions/${sid}/scene`)).environment;
    await page.selectOption('#environment .env-name', 'studio');
    await until('studio', async () => (await envNow()).name === 'studio');
    await page.fill('#environment .env-intensity', '2');
    await page.press('#environment .env-intensity', 'Enter');
    await page.fill('#environment .env-rotation', '90');
    await page.press('#environment .env-rotation', 'Enter');
    await page.uncheck('#environment .env-visible');
    await until('intensity 2, rotation 90, hidden background', async () => {
      const e = await envNow();
      return e.intensity === 2 && e.rotation === 90 && e.visible === false;
    });
    // An uploaded equirect HDR (flat RGBE scanlines, 16 x 8: upper half 2.0, lower half black)
    // becomes the environment.
    const rows = [];
    for (let y = 0; y < 8; ++y) for (let x = 0; x < 16; ++x) rows.push(...(y < 4 ? [128, 128, 128, 130] : [0, 0, 0, 0]));
    const hdr = Buffer.concat([Buffer.from('#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n'), Buffer.from(rows)]);
    await page.setInputFiles('#environment .env-upload', { name: 'half.hdr', mimeType: 'application/octet-stream', buffer: hdr });
    const uploaded = await until('the upload listed', async () =>
      (await http(env, 'GET', '/api/assets?kind=environment')).find((a) => a.name === 'half.hdr'));
    await until('the scene to use it', async () => (await envNow()).name === uploaded.id);
    await shot(env, page, '12-environment');
    await page.click('.tabs [data-tab="tab-editor"]');
  }],

  ['a hidden tab closes its stream and stops polling stats; showing it resumes', async (env) => {
    const page = env.page2;
    const sid = new URL(page.url()).searchParams.get('session');
    await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { render: { max_samples: 1048576 } });   // frames flow
    await until('a stream client', async () => (await http(env, 'GET', `/api/sessions/${sid}`)).stream_clients >= 1);
    const setHidden = (hidden) => page.evaluate((hidden) => {
      Object.defineProperty(document, 'visibilityState', { configurable: true, get: () => (hidden ? 'hidden' : 'visible') });
      document.dispatchEvent(new Event('visibilitychange'));
    }, hidden);
    await setHidden(true);
    await until('the stream to close', async () => (await http(env, 'GET', `/api/sessions/${sid}`)).stream_clients === 0);
    const polls = () => page.evaluate(() => performance.getEntriesByType('resource').filter((r) => r.name.includes('/stats')).length);
    await sleep(300);
    const n0 = await polls();
    await sleep(1500);
    assert.equal(await polls(), n0, 'no stats requests while hidden');
    assert.match(await page.locator('#viewer .overlay').textContent(), /paused/);
    await setHidden(false);
    await until('the stream to reconnect', async () => (await http(env, 'GET', `/api/sessions/${sid}`)).stream_clients >= 1);
    await until('stats polled again', async () => (await polls()) > n0);
    await capSamples(env, sid);
  }],

  ['the convergence plot grows while rendering; sampling and target error in the render settings', async (env) => {
    const { page, sid } = env;
    const stats = () => http(env, 'GET', `/api/sessions/${sid}/stats`);
    const scene = () => http(env, 'GET', `/api/sessions/${sid}/scene`);
    await http(env, 'PATCH', `/api/sessions/${sid}/scene`, { render: { max_samples: 1048576 } });   // keeps rendering
    await page.click('.tabs [data-tab="tab-convergence"]');
    const count = () => page.evaluate(() => Number(document.querySelector('#convergence .conv-plot').dataset.points || 0));
    const n1 = await until('points on the plot', async () => { const n = await count(); return n >= 3 && n; });
    await until('more points on the plot', async () => (await count()) > n1);
    await page.locator('#convergence .conv-plot canvas').first().waitFor();
    await until('the fitted slope', async () => /slope -\d/.test(await page.locator('#convergence .conv-fit').textContent()));
    await shot(env, page, '13-convergence');

    // The sampling selector PATCHes render.sampling: the accumulation and the stream restart.
    await page.click('.tabs [data-tab="tab-objects"]');
    assert.equal(await page.inputValue('#objects .r-sampling'), 'mis', 'the default mode is shown');
    const before = await until('some samples', async () => { const s = await stats(); return s.spp >= 100 && s.spp; });
    await page.selectOption('#objects .r-sampling', 'uniform');
    await until('the scene to sample uniformly', async () => (await scene()).render.sampling === 'uniform');
    const overlaySpp = async () => Number((/^(\d+) spp/.exec(await page.locator('#viewer .overlay').textContent()) || [])[1] ?? NaN);
    await until('the view to restart from few samples', async () => (await overlaySpp()) < before);
    await page.selectOption('#objects .r-sampling', 'mis');
    await until('back to mis', async () => (await scene()).render.sampling === 'mis');

    // A target error (in percent) stops rendering once reached; the overlay says so.
    await page.fill('#objects .r-target', '90');
    await page.press('#objects .r-target', 'Enter');
    await until('target_error 0.9 in the scene', async () => (await scene()).render.target_error === 0.9);
    await until('converged', async () => (await stats()).converged);
    await until('the overlay to say so', async () => /err [\d.]+%.*converged/.test(await page.locator('#viewer .overlay').textContent()));
    await page.fill('#objects .r-target', '');
    await page.press('#objects .r-target', 'Enter');
    await until('no target', async () => (await scene()).render.target_error === null);

    // The strategy comparison runs as a job and lists each mode.
    await page.click('.tabs [data-tab="tab-convergence"]');
    await page.fill('#convergence .cmp-time', '100');
    await page.click('#convergence .cmp-run');
    await until('a row per mode', async () => (await page.locator('#convergence .cmp-results tbody tr').count()) === 4, 60000);
    assert.equal(await page.locator('#convergence .cmp-status').textContent(), 'done');
    await shot(env, page, '14-strategies');
    await capSamples(env, sid);
    await page.click('.tabs [data-tab="tab-editor"]');
  }],

  ['no console errors', async (env) => {
    // Chromium logs every 4xx answer to fetch as "Failed to load resource"; the 422 of the
    // syntax-error check is the API's expected answer to bad source, not a UI error.
    const expected = /Failed to load resource: .*status of 422/;
    const errors = env.context.pages().flatMap((p) => p.errors || []).filter((e) => !expected.test(e));
    assert.deepEqual(errors, []);
  }],
];
