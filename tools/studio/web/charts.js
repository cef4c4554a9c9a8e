// Chart frames on Debian's d3 (libjs-d3, version 3): axes with titles in an SVG, and the viridis colour map the
// CLI's pictures use (tools/plot/heat_map.cpp), so that colours read the same in the studio and in PNGs.
"use strict";

// Clears `svg` and draws axes for x in xDomain and y in yDomain; returns the plot group and the scales.
Studio.frame = function (svg, xDomain, yDomain, xLabel, yLabel, options) {
  options = options || {};
  const root = d3.select(svg);
  root.selectAll("*").remove();
  const width = +svg.getAttribute("width"), height = +svg.getAttribute("height");
  const margin = Object.assign({ top: options.title ? 30 : 12, right: 16, bottom: 46, left: 62 }, options.margin || {});
  const w = width - margin.left - margin.right, h = height - margin.top - margin.bottom;
  const x = d3.scale.linear().domain(xDomain).range([0, w]);
  const y = d3.scale.linear().domain(yDomain).range([h, 0]);
  if (options.nice !== false) {
    x.nice();
    y.nice();
  }
  if (options.title) root.append("text").attr("class", "chart-title").attr("x", margin.left).attr("y", 18).text(options.title);
  const g = root.append("g").attr("transform", "translate(" + margin.left + "," + margin.top + ")");
  if (options.grid !== false)
    g.append("g").attr("class", "grid").call(d3.svg.axis().scale(y).orient("left").ticks(6).tickSize(-w).tickFormat(""));
  g.append("g").attr("class", "axis").attr("transform", "translate(0," + h + ")")
    .call(d3.svg.axis().scale(x).orient("bottom").ticks(8).tickFormat(Studio.tickFormat(x, 8)));
  g.append("g").attr("class", "axis").call(d3.svg.axis().scale(y).orient("left").ticks(6).tickFormat(Studio.tickFormat(y, 6)));
  g.append("text").attr("class", "axis-title").attr("x", w / 2).attr("y", h + 38).attr("text-anchor", "middle").text(xLabel);
  g.append("text").attr("class", "axis-title").attr("transform", "rotate(-90)").attr("x", -h / 2).attr("y", -46)
    .attr("text-anchor", "middle").text(yLabel);
  return { root: root, g: g, x: x, y: y, width: w, height: h, margin: margin };
};

// d3's tick labels, with zero written "0": d3 3.5 reaches the tick at zero by adding steps, so it can be -1e-17,
// which its format writes "-0.0".
Studio.tickFormat = function (scale, count) {
  const format = scale.tickFormat(count), domain = scale.domain();
  const tiny = 1e-9 * Math.abs(domain[1] - domain[0]);
  return (v) => format(Math.abs(v) < tiny ? 0 : v);
};

// [lo, hi] of the finite values, widened by 5% (or to a unit span when flat) so that no point sits on the frame.
Studio.padded = function (values) {
  const finite = values.filter((v) => v !== null && Number.isFinite(v));
  let lo = Math.min.apply(null, finite), hi = Math.max.apply(null, finite);
  if (!finite.length) return [0, 1];
  if (!(hi > lo)) { lo -= 0.5; hi += 0.5; }
  const margin = (hi - lo) * 0.05;
  return [lo - margin, hi + margin];
};

// Tableau 10, as tools/plot/canvas.cpp's categorical_colour.
Studio.colours = ["#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f", "#edc948", "#b07aa1", "#ff9da7", "#9c755f", "#bab0ac"];

// Viridis at t in [0, 1] (van der Walt and Smith), by linear interpolation of 9 anchors; grey for NaN.
Studio.viridis = function (t) {
  if (t === null || Number.isNaN(t)) return [0.6, 0.6, 0.6];
  const anchors = [[0.267, 0.005, 0.329], [0.283, 0.141, 0.458], [0.254, 0.265, 0.530], [0.207, 0.372, 0.553],
    [0.164, 0.471, 0.558], [0.128, 0.567, 0.551], [0.135, 0.659, 0.518], [0.267, 0.749, 0.441],
    [0.478, 0.821, 0.318], [0.741, 0.873, 0.150], [0.993, 0.906, 0.144]];
  const s = Math.min(Math.max(t, 0), 1) * (anchors.length - 1);
  const k = Math.min(Math.floor(s), anchors.length - 2), f = s - k;
  return anchors[k].map((c, i) => c + (anchors[k + 1][i] - c) * f);
};

Studio.rgb = function (colour) {
  return "rgb(" + colour.map((c) => Math.round(c * 255)).join(",") + ")";
};
