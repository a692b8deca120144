// Bundles the UI (src/main.js and the npm packages it imports: CodeMirror 6) into dist/, which
// is ignored by git: dependencies come from npm at build time, never from committed bundles
// (docs/design.md section 2). esbuild is quick, so `make` and the browser test may run it freely.
// Code splitting: main.js stays small and starts the session and stream at once; the editor
// (CodeMirror, most of the bytes) arrives as a chunk through a dynamic import meanwhile, and
// uPlot (the convergence plot) when its tab is first shown, with its stylesheet as dist/uplot.css.
import { build } from 'esbuild';
import { rmSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));

rmSync(join(here, 'dist'), { recursive: true, force: true });   // no stale chunks
await build({
  entryPoints: [
    { in: join(here, 'src/main.js'), out: 'main' },
    { in: join(here, 'node_modules/uplot/dist/uPlot.min.css'), out: 'uplot' },
  ],
  outdir: join(here, 'dist'),
  bundle: true,
  format: 'esm',
  splitting: true,
  chunkNames: 'chunk-[hash]',
  target: 'es2020',
  minify: true,
  sourcemap: true,      // readable stack traces in the browser's console
  logLevel: 'warning',
});
