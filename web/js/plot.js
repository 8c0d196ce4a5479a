// Live plot of the five joint angles (degrees) over a sliding time window, drawn with uPlot
// (loaded as a global from /node_modules/uplot/dist/uPlot.iife.min.js).

const COLORS = ["#3d8bfd", "#2fbf71", "#e0a030", "#e5484d", "#b07cff"];
const REDRAW_INTERVAL_MS = 100;

export class JointPlot {
  constructor(container, { windowS = 20, jointNames = ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"] } = {}) {
    this.container = container;
    this.windowS = windowS;
    this.jointNames = jointNames;
    this.timesS = [];
    this.series = jointNames.map(() => []);
    this.lastDrawMs = 0;
    this.plot = null;
    const UPlot = window.uPlot;
    if (typeof UPlot !== "function") {
      container.textContent = "uPlot not loaded: run `npm ci` in web/ (scripts/setup does).";
      container.classList.add("plot-missing");
      return;
    }
    this.plot = new UPlot(this.options(), [[], ...jointNames.map(() => [])], container);
    new ResizeObserver(() => this.resize()).observe(container);
  }

  options() {
    const width = Math.max(300, this.container.clientWidth || 600);
    return {
      width,
      height: 170,
      legend: { live: false },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false }, y: { auto: true } },
      axes: [
        {
          stroke: "#8a96a6",
          grid: { stroke: "#232933" },
          incrs: [1, 2, 5, 10],
          values: (u, ticks) => ticks.map((t) => `${t.toFixed(0)}s`),
        },
        { stroke: "#8a96a6", grid: { stroke: "#232933" }, size: 44 },
      ],
      series: [{ label: "t" }, ...this.jointNames.map((name, i) => ({ label: name, stroke: COLORS[i % COLORS.length], width: 1.5 }))],
    };
  }

  resize() {
    if (!this.plot) return;
    const width = Math.max(300, this.container.clientWidth);
    if (Math.abs(width - this.plot.width) > 2) this.plot.setSize({ width, height: 170 });
  }

  /** Add one sample (time in seconds, joint angles in radians); redraws at most every 100 ms. */
  push(timeS, jointsRad) {
    if (!Number.isFinite(timeS) || !Array.isArray(jointsRad)) return;
    if (this.timesS.length && timeS <= this.timesS[this.timesS.length - 1]) return;
    this.timesS.push(timeS);
    this.series.forEach((s, i) => s.push(Number.isFinite(jointsRad[i]) ? (jointsRad[i] * 180) / Math.PI : null));
    while (this.timesS.length && timeS - this.timesS[0] > this.windowS) {
      this.timesS.shift();
      this.series.forEach((s) => s.shift());
    }
    const nowMs = performance.now();
    if (this.plot && nowMs - this.lastDrawMs >= REDRAW_INTERVAL_MS) {
      this.lastDrawMs = nowMs;
      const t0 = this.timesS[this.timesS.length - 1];
      const relS = this.timesS.map((t) => t - t0);
      this.plot.setData([relS, ...this.series]);
    }
  }

  get sampleCount() {
    return this.timesS.length;
  }
}
