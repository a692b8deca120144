// uPlot (the convergence and albedo plots) and its stylesheet, loaded on first use: never
// before the first frame, and once for every plot that needs it.
let uplot = null;   // Promise of the uPlot class

export function loadUplot() {
  if (!uplot) {
    const link = document.createElement('link');
    link.rel = 'stylesheet';
    link.href = 'dist/uplot.css';   // bundled by build.mjs from the npm package
    document.head.append(link);
    uplot = import('uplot').then((m) => m.default);
  }
  return uplot;
}
