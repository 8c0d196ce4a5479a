// Live plot of the joint angles (degrees) over a sliding time window, drawn with uPlot (loaded as a
// global from /node_modules/uplot/dist/uPlot.iife.min.js). The y range is fixed to the joint limits the
// server sends (status joint_limits_rad), so a still arm is a flat line, not noise blown up to full scale.

const COLORS = ["#3d8bfd", "#2fbf71", "#e0a030", "#e5484d", "#b07cff", "#4fd1c5"];
const REDRAW_INTERVAL_MS = 100;
const PLOT_HEIGHT_PX = 150;
const DEG_PER_RAD = 180 / Math.PI;

/** [min, max] degrees covering every joint's limits (radians pairs from the server), or null. */
export function yRangeFromLimits(limitsRad) {
  if (!Array.isArray(limitsRad) || !limitsRad.length) return null;
  const flat = limitsRad.flat();
  if (!flat.length || !flat.every(Number.isFinite)) return null;
  return [Math.min(...flat) * DEG_PER_RAD, Math.max(...flat) * DEG_PER_RAD];
}

export class JointPlot {
  constructor(container, { windowS = 20, jointNames = [] } = {}) {
    this.container = container;
    this.windowS = windowS;
    this.jointNames = jointNames;
    this.yRangeDeg = null;
    this.timesS = [];
    this.series = [];
    this.lastDrawMs = 0;
    this.plot = null;
    if (typeof window.uPlot !== "function") {
      container.textContent = "uPlot not loaded: run `npm ci` in web/ (scripts/setup does).";
      container.classList.add("plot-missing");
      return;
    }
    new ResizeObserver(() => this.resize()).observe(container);
    this.rebuild();
  }

  /** Joint names and limits (radians) from the server's status: rebuilds the series, fixes the y range. */
  setJoints(names, limitsRad) {
    const range = yRangeFromLimits(limitsRad);
    const sameNames = Array.isArray(names) && names.join() === this.jointNames.join();
    const sameRange = range && this.yRangeDeg && range.every((v, i) => v === this.yRangeDeg[i]);
    if (sameNames && sameRange) return;
    if (Array.isArray(names)) this.jointNames = names;
    this.yRangeDeg = range;
    this.rebuild();
  }

  rebuild() {
    this.timesS = [];
    this.series = this.jointNames.map(() => []);
    if (typeof window.uPlot !== "function") return;
    this.plot?.destroy();
    this.plot = new window.uPlot(this.options(), [[], ...this.series], this.container);
  }

  options() {
    const width = Math.max(300, this.container.clientWidth || 600);
    const fixed = this.yRangeDeg;
    return {
      width,
      height: PLOT_HEIGHT_PX,
      legend: { live: false },
      cursor: { drag: { x: false, y: false } },
      scales: {
        x: { time: false },
        y: { auto: !fixed, range: fixed ? () => [...fixed] : undefined },
      },
      axes: [
        {
          stroke: "#8a96a6",
          grid: { stroke: "#232933" },
          incrs: [1, 2, 5, 10],
          values: (u, ticks) => ticks.map((t) => `${t.toFixed(0)}s`),
        },
        { stroke: "#8a96a6", grid: { stroke: "#232933" }, size: 52, space: 18, incrs: [15, 30, 45, 90, 180, 360], values: (u, ticks) => ticks.map((t) => `${t.toFixed(0)}°`) },
      ],
      series: [
        { label: "t" },
        ...this.jointNames.map((name, i) => ({ label: name, stroke: COLORS[i % COLORS.length], width: 1.5 })),
      ],
    };
  }

  resize() {
    if (!this.plot) return;
    const width = Math.max(300, this.container.clientWidth);
    if (Math.abs(width - this.plot.width) > 2) this.plot.setSize({ width, height: PLOT_HEIGHT_PX });
  }

  /** Add one sample (time in seconds, joint angles in radians); redraws at most every 100 ms. */
  push(timeS, jointsRad) {
    if (!Number.isFinite(timeS) || !Array.isArray(jointsRad)) return;
    if (this.timesS.length && timeS <= this.timesS[this.timesS.length - 1]) return;
    this.timesS.push(timeS);
    this.series.forEach((s, i) => s.push(Number.isFinite(jointsRad[i]) ? jointsRad[i] * DEG_PER_RAD : null));
    while (this.timesS.length && timeS - this.timesS[0] > this.windowS) {
      this.timesS.shift();
      this.series.forEach((s) => s.shift());
    }
    const nowMs = performance.now();
    if (this.plot && nowMs - this.lastDrawMs >= REDRAW_INTERVAL_MS) {
      this.lastDrawMs = nowMs;
      const t0 = this.timesS[this.timesS.length - 1];
      this.plot.setData([this.timesS.map((t) => t - t0), ...this.series]);
    }
  }

  /** The y axis range now shown, degrees [min, max]. */
  get yRange() {
    return this.plot ? [this.plot.scales.y.min, this.plot.scales.y.max] : null;
  }

  get sampleCount() {
    return this.timesS.length;
  }
}
