// Starts the real brdfa-server on a free port (--port 0) with a throw-away data folder and
// resolves with its base URL once it prints `listening on http://HOST:PORT` (docs/api.md).
// `args`: more command-line flags (auth.mjs: --auth tokens --admin-token-file F).
import { spawn } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

export async function startServer(binary, root, { args = [] } = {}) {
  const dataDir = mkdtempSync(join(tmpdir(), 'brdfa-web-'));
  const proc = spawn(binary, ['--port', '0', '--root', root, '--data-dir', dataDir, ...args], {
    stdio: ['ignore', 'pipe', 'pipe'],
  });
  let stderr = '';
  proc.stderr.on('data', (d) => { stderr = (stderr + d).slice(-20000); });
  const url = await new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error(`server did not start in 30 s:\n${stderr}`)), 30000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/listening on (http:\/\/\S+)/);
      if (m) { clearTimeout(timer); resolve(m[1]); }
    });
    proc.on('exit', (code) => { clearTimeout(timer); reject(new Error(`server exited ${code}:\n${stderr}`)); });
  });
  return {
    url,
    dataDir,
    stderr: () => stderr,
    async stop() {
      proc.removeAllListeners('exit');
      const done = new Promise((r) => proc.once('exit', r));
      proc.kill('SIGTERM');
      await Promise.race([done, new Promise((r) => setTimeout(r, 10000))]);
      if (proc.exitCode === null) proc.kill('SIGKILL');
      rmSync(dataDir, { recursive: true, force: true });
    },
  };
}

// The end of a browser test: the server's log tail and exit 1 when `failed` checks failed.
export function reportAndExit(failed, server, artifacts) {
  if (failed) {
    console.log(`server log (tail):\n${server.stderr().slice(-3000)}`);
    console.log(`${failed} check(s) failed; screenshots in ${artifacts}`);
    process.exit(1);
  }
  console.log(`all checks passed; screenshots in ${artifacts}`);
}
