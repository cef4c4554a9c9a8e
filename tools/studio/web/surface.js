// The control surface over two inputs (the server's control_surface, as `fmpc plot --x --y`), the other inputs at the
// patient panel's values, as a heat map in the CLI's viridis colours; points where no rule fires at lint's
// coverage threshold are hatched. Hovering reads the exact value off the grid.
"use strict";

Studio.surface = { answer: null };

Studio.surface.request = Studio.latest(async function () {
  const system = Studio.system();
  if (!system || system.inputs.length < 2) {
    document.getElementById("surface-readout").textContent = system ? "A surface needs two inputs; this system has one." : "";
    return;
  }
  const x = Number(document.getElementById("surface-x").value), y = Number(document.getElementById("surface-y").value);
  if (x === y) {
    document.getElementById("surface-readout").textContent = "Pick two different inputs.";
    return;
  }
  try {
    const answer = await Studio.call("/api/surface", Studio.rulesRequest({
      x: x, y: y, output: Number(document.getElementById("surface-output").value), point: Studio.state.patient,
      resolution: Number(document.getElementById("surface-resolution").value),
    }));
    Studio.surface.answer = { grid: answer, x: x, y: y, output: Number(document.getElementById("surface-output").value) };
    Studio.surface.draw(system);
  } catch (error) {
    Studio.message(error.message, "bad");
  }
});

Studio.surface.draw = function (system) {
  const s = Studio.surface.answer;
  const grid = s.grid;
  const vx = system.inputs[s.x], vy = system.inputs[s.y], out = system.outputs[s.output];
  const svg = document.getElementById("surface-axes");
  const label = (v) => v.name + (v.unit && v.unit !== "dimensionless" ? " (" + v.unit + ")" : "");
  const f = Studio.frame(svg, [vx.min, vx.max], [vy.min, vy.max], label(vx), label(vy), { nice: false, grid: false, margin: { right: 150, top: 24 },
    title: out.name + " over " + vx.name + " and " + vy.name });
  const finite = grid.z.filter((z) => z !== null);
  const lo = d3.min(finite), hi = d3.max(finite) > lo ? d3.max(finite) : lo + 1;
  const canvas = document.getElementById("surface-canvas");
  canvas.width = Math.round(f.width);
  canvas.height = Math.round(f.height);
  canvas.style.left = f.margin.left + "px";
  canvas.style.top = f.margin.top + "px";
  const context = canvas.getContext("2d");
  const n = grid.x.length, m = grid.y.length;
  const cellW = canvas.width / (n - 1), cellH = canvas.height / (m - 1);
  for (let r = 0; r < m; ++r)
    for (let c = 0; c < n; ++c) {
      const z = grid.z[r * n + c];
      context.fillStyle = Studio.rgb(Studio.viridis(z === null ? NaN : (z - lo) / (hi - lo)));
      context.fillRect((c - 0.5) * cellW, canvas.height - (r + 0.5) * cellH, cellW + 1, cellH + 1);
    }
  // Coverage holes: diagonal hatching over the cells where the strongest rule stays under the threshold.
  context.strokeStyle = "rgba(255,255,255,0.85)";
  context.lineWidth = 1;
  let holes = 0;
  for (let r = 0; r < m; ++r)
    for (let c = 0; c < n; ++c) {
      if (grid.strongest_firing[r * n + c] >= grid.threshold) continue;
      ++holes;
      const x0 = (c - 0.5) * cellW, y0 = canvas.height - (r + 0.5) * cellH;
      context.beginPath();
      context.moveTo(x0, y0 + cellH);
      context.lineTo(x0 + cellW, y0);
      context.stroke();
    }
  // Colour bar.
  const bar = f.root.append("g").attr("transform", "translate(" + (f.margin.left + f.width + 24) + "," + f.margin.top + ")");
  const barScale = d3.scale.linear().domain([lo, hi]).range([f.height, 0]);
  for (let k = 0; k < 100; ++k)
    bar.append("rect").attr("x", 0).attr("y", f.height * (1 - (k + 1) / 100)).attr("width", 16).attr("height", f.height / 100 + 1)
      .attr("fill", Studio.rgb(Studio.viridis((k + 0.5) / 100)));
  bar.append("g").attr("class", "axis").attr("transform", "translate(16,0)").call(d3.svg.axis().scale(barScale).orient("right").ticks(6));
  bar.append("text").attr("class", "axis-title").attr("transform", "rotate(-90)").attr("x", -f.height / 2).attr("y", 66)
    .attr("text-anchor", "middle").text(label(out));
  const fixed = system.inputs.map((v, i) => i === s.x || i === s.y ? null : v.name + " = " + Studio.withUnit(String(Studio.state.patient[i]), v.unit))
    .filter((t) => t);
  document.getElementById("surface-fixed").textContent = fixed.length ? fixed.join(", ") : "none";
  document.getElementById("surface-threshold").textContent = grid.threshold;
  document.getElementById("surface-readout").textContent = holes + " of " + n * m + " grid points are coverage holes" +
    (grid.nan_points ? "; " + grid.nan_points + " evaluate to NaN (no rule fired under the policy 'error'; grey)" : "") +
    ". Point at the map to read a value.";
  canvas.onmousemove = (event) => {
    const c = Math.round(event.offsetX / cellW), r = Math.round((canvas.height - event.offsetY) / cellH);
    if (c < 0 || c >= n || r < 0 || r >= m) return;
    const z = grid.z[r * n + c], w = grid.strongest_firing[r * n + c];
    document.getElementById("surface-readout").textContent = vx.name + " = " + grid.x[c] + ", " + vy.name + " = " + grid.y[r] +
      ": " + out.name + " = " + Studio.withUnit(z === null ? "NaN" : String(z), out.unit) +
      "; strongest rule fires at " + Studio.four(w) + (w < grid.threshold ? " (a coverage hole)" : "");
  };
};

Studio.on("model", (system) => {
  const inputs = system.inputs.map((v, i) => ({ value: String(i), label: v.name }));
  const xs = document.getElementById("surface-x"), ys = document.getElementById("surface-y"), os = document.getElementById("surface-output");
  Studio.fillSelect(xs, inputs, xs.value || "0");
  Studio.fillSelect(ys, inputs, ys.value || (inputs.length > 1 ? "1" : "0"));
  Studio.fillSelect(os, system.outputs.map((v, i) => ({ value: String(i), label: v.name })), os.value || "0");
  if (Studio.state.tab === "surface") Studio.surface.request();
});
Studio.on("tab", (tab) => { if (tab === "surface") Studio.surface.request(); });

document.addEventListener("DOMContentLoaded", () => {
  for (const id of ["surface-x", "surface-y", "surface-output", "surface-resolution"])
    document.getElementById(id).addEventListener("change", () => Studio.surface.request());
});
