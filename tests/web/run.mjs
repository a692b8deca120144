// Browser tests of the UI in Debian's Chromium, driven by playwright-core, against
// the real server binary. Registered in CTest as `web_ui` (tests/CMakeLists.txt):
//   node tests/web/run.mjs --server build/server/brdfa-server --root . --artifacts build/web-artifacts
// Rebuilds web/dist first (esbuild is quick) so it always tests the current sources. Prints the
// UI's timings (page load -> first frame, slider -> updated frame) and saves
// screenshots of the main states into --artifacts. Exit 0 pass, 1 fail, 77 skipped (no browser).
import { existsSync, mkdirSync } from 'node:fs';
import { createRequire } from 'node:module';
import { join, resolve } from 'node:path';
import { execFileSync } from 'node:child_process';
import { reportAndExit, startServer } from './server.mjs';
import { grab, variance, meanDiff, waitForFrame } from './frames.mjs';
import { checks } from './checks.mjs';
import { layoutChecks } from './layout.mjs';
import { analysisChecks } from './analysis.mjs';
import { sceneEditChecks } from './scene_edits.mjs';

const CHROMIUM = process.env.BRDFA_CHROMIUM || '/usr/bin/chromium';

function args() {
  const out = { server: process.env.BRDFA_SERVER_BINARY, root: process.env.BRDFA_ROOT, artifacts: 'web-artifacts' };
  const a = process.argv.slice(2);
  for (let i = 0; i < a.length; i += 2) out[a[i].replace(/^--/, '')] = a[i + 1];
  if (!out.server || !out.root) {
    console.error('usage: run.mjs --server BINARY --root SOURCE_DIR [--artifacts DIR]');
    process.exit(2);
  }
  return { ...out, root: resolve(out.root), artifacts: resolve(out.artifacts) };
}

async function main() {
  const opt = args();
  if (!existsSync(CHROMIUM)) {
    // docker/install-deps.sh installs it; without it there is nothing to drive.
    console.log(`SKIP: ${CHROMIUM} not found (apt-get install chromium)`);
    process.exit(77);
  }
  // playwright-core lives in web/node_modules (web/package.json devDependencies).
  const require = createRequire(join(opt.root, 'web', 'package.json'));
  const { chromium } = require('playwright-core');
  execFileSync(process.execPath, [join(opt.root, 'web', 'build.mjs')], { stdio: 'inherit' });
  mkdirSync(opt.artifacts, { recursive: true });

  const server = await startServer(opt.server, opt.root);
  const browser = await chromium.launch({
    executablePath: CHROMIUM,
    headless: true,
    // Root in a container: no user namespaces for the sandbox; /dev/shm may be tiny.
    args: ['--no-sandbox', '--disable-dev-shm-usage'],
  });
  let failed = 0;
  try {
    const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });
    const env = { server, context, artifacts: opt.artifacts, grab, variance, meanDiff, waitForFrame };
    for (const [name, fn] of [...checks, ...sceneEditChecks, ...layoutChecks, ...analysisChecks]) {
      const t = Date.now();
      try {
        await fn(env);
        console.log(`ok   ${name} (${Date.now() - t} ms)`);
      } catch (e) {
        failed++;
        console.log(`FAIL ${name}: ${e.stack || e}`);
        for (const p of context.pages()) {
          await p.screenshot({ path: join(opt.artifacts, `fail-${name.replace(/\W+/g, '_')}-${context.pages().indexOf(p)}.png`) }).catch(() => {});
        }
        if (env.fatal) break;   // later checks need what this one set up
      }
    }
  } finally {
    await browser.close();
    await server.stop();
  }
  reportAndExit(failed, server, opt.artifacts);
}

main().catch((e) => { console.error(e); process.exit(1); });
