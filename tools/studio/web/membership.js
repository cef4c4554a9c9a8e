// Membership functions drawn per variable (the grades come from the server's term_membership), with handles to drag
// and fields to type; coverage holes of an input (lint's check) shaded. A drag or a typed value rewrites only that
// parameter's number in the text.
"use strict";

Studio.membership = { variable: "", term: "", curves: null, curvesText: null };

// Families whose positions must stay in order (start <= peak <= end, ...): a handle stops at its neighbours.
Studio.membership.ordered = ["triangle", "trapezoid", "pishape", "zshape", "sshape", "linear_s", "linear_z"];

Studio.membership.current = function () {
  const system = Studio.system();
  if (!system) return null;
  const m = Studio.membership;
  const input = system.inputs.find((v) => v.name === m.variable);
  const output = system.outputs.find((v) => v.name === m.variable);
  return input ? { variable: input, output: false, system: system } : output ? { variable: output, output: true, system: system } : null;
};

Studio.membership.fetch = Studio.latest(async function () {
  const m = Studio.membership;
  const text = Studio.editor.getValue();
  if (!m.variable || !Studio.system()) return;
  try {
    m.curves = await Studio.call("/api/memberships", Studio.rulesRequest({ variable: m.variable, text: text }));
    m.curvesText = text;
    Studio.membership.draw();
  } catch (error) {
    Studio.message(error.message, "bad");
  }
});

// The grade of `term` at x, read off the server's samples (linear between them).
Studio.membership.gradeAt = function (termCurve, x) {
  const xs = Studio.membership.curves.x;
  if (!termCurve.upper) return 0;
  let k = d3.bisectLeft(xs, x);
  if (k <= 0) return termCurve.upper[0];
  if (k >= xs.length) return termCurve.upper[xs.length - 1];
  const f = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
  return termCurve.upper[k - 1] + f * (termCurve.upper[k] - termCurve.upper[k - 1]);
};

// Where each draggable parameter of `term` sits: {name, x, anchor (for widths), sign}.
Studio.membership.handles = function (term) {
  const value = (name) => (term.parameters.find((p) => p.name === name) || {}).value;
  const handles = [];
  for (const p of term.parameters) {
    if (p.role === "position") handles.push({ name: p.name, x: p.value, kind: "position" });
    if (p.role === "width") {
      const anchorName = { sd: "mean", sd1: "mean1", sd2: "mean2", width: "center" }[p.name];
      const sign = p.name === "sd1" ? -1 : 1;
      handles.push({ name: p.name, x: value(anchorName) + sign * p.value, anchor: value(anchorName), sign: sign, kind: "width" });
    }
  }
  return handles;
};

// A value dragged to `x`: rounded to a thousandth of the range, so that the text reads 7.65 and not 7.6534912.
Studio.membership.rounded = function (x, variable) {
  const step = Math.pow(10, Math.floor(Math.log10((variable.max - variable.min) / 1000)));
  return Number((Math.round(x / step) * step).toPrecision(12));
};

Studio.membership.setParameter = Studio.latest(async function (change) {
  try {
    const answer = await Studio.call("/api/edit", Studio.rulesRequest({
      operation: "set_parameter", variable: change.variable, term: change.term, parameter: change.parameter, value: change.value,
    }));
    Studio.setText(answer.text);
    Studio.membership.fetch();
  } catch (error) {
    Studio.message(error.message, "bad");
  }
});

Studio.membership.draw = function () {
  const m = Studio.membership;
  const current = m.current();
  const svg = document.getElementById("membership-chart");
  if (!current || !m.curves || m.curves.variable !== current.variable.name) return;
  const v = current.variable;
  const unit = v.unit && v.unit !== "dimensionless" ? " (" + v.unit + ")" : "";
  const f = Studio.frame(svg, [v.min, v.max], [0, 1.05], v.name + unit, "degree of membership",
    { nice: false, title: (current.output ? "output " : "input ") + v.name + (v.description ? ": " + v.description : ""), margin: { right: 130 } });
  const sugeno = current.output && current.system.sugeno;
  if (!current.output)
    for (const hole of v.coverage_holes || []) {
      const x0 = f.x(hole[0]), x1 = Math.max(f.x(hole[1]), x0 + 2);
      f.g.append("rect").attr("class", "hole").attr("x", x0).attr("y", 0).attr("width", x1 - x0).attr("height", f.height)
        .append("title").text("coverage hole: no term reaches " + v.coverage_threshold + " on [" + hole[0] + ", " + hole[1] + "]");
    }
  const line = d3.svg.line().x((d) => f.x(d[0])).y((d) => f.y(d[1]));
  const area = d3.svg.area().x((d) => f.x(d[0])).y0((d) => f.y(d[1])).y1((d) => f.y(d[2]));
  m.curves.terms.forEach((curve, t) => {
    const colour = Studio.colours[t % Studio.colours.length];
    const selected = curve.name === m.term;
    const group = f.g.append("g").attr("class", "term" + (selected ? " selected" : "")).style("cursor", "pointer")
      .on("click", () => { m.term = curve.name; Studio.membership.refreshTerms(); Studio.membership.draw(); });
    if (sugeno) {
      const constant = curve.family === "constant" ? curve.parameters[0].value : null;
      if (constant !== null)
        group.append("line").attr("x1", f.x(constant)).attr("x2", f.x(constant)).attr("y1", f.y(0)).attr("y2", f.y(1))
          .attr("stroke", colour).attr("stroke-width", selected ? 4 : 2);
    } else {
      const points = m.curves.x.map((x, k) => [x, curve.upper[k], curve.lower ? curve.lower[k] : curve.upper[k]]);
      if (curve.lower) group.append("path").attr("d", area(points)).attr("fill", colour).attr("opacity", 0.25);
      group.append("path").attr("d", line(points)).attr("fill", "none").attr("stroke", colour).attr("stroke-width", selected ? 3.5 : 1.8);
    }
    f.root.append("text").attr("class", "legend" + (selected ? " selected" : "")).attr("x", +svg.getAttribute("width") - 120)
      .attr("y", f.margin.top + 16 + 18 * t).attr("fill", colour).text((selected ? "▶ " : "") + curve.name)
      .style("cursor", "pointer").on("click", () => { m.term = curve.name; Studio.membership.refreshTerms(); Studio.membership.draw(); });
  });
  // The handles from the same answer as the curves (the model of the last check may be a moment older).
  const term = m.curves.terms.find((c) => c.name === m.term);
  if (!term || term.type2 || sugeno) return;
  const curve = term;
  const handles = Studio.membership.handles(term);
  const positions = handles.filter((h) => h.kind === "position");
  const ordered = Studio.membership.ordered.includes(term.family);
  const drag = d3.behavior.drag().on("drag", function (h) {
    let x = Math.min(Math.max(f.x.invert(d3.event.x), v.min - (v.max - v.min)), v.max + (v.max - v.min));
    if (ordered && h.kind === "position") {
      const k = positions.indexOf(h);
      if (k > 0) x = Math.max(x, positions[k - 1].x);
      if (k + 1 < positions.length) x = Math.min(x, positions[k + 1].x);
    }
    let value = Studio.membership.rounded(x, v);
    if (h.kind === "width") value = Math.max(Studio.membership.rounded(Math.abs(x - h.anchor), v), (v.max - v.min) / 1000);
    h.x = h.kind === "width" ? h.anchor + h.sign * value : value;
    d3.select(this).attr("cx", f.x(h.x));
    Studio.membership.setParameter({ variable: v.name, term: term.name, parameter: h.name, value: value });
  });
  f.g.selectAll("circle.handle").data(handles).enter().append("circle")
    .attr("class", (h) => "handle " + h.kind).attr("data-parameter", (h) => h.name)
    .attr("cx", (h) => f.x(h.x)).attr("cy", (h) => f.y(Math.min(Studio.membership.gradeAt(curve, h.x), 1)))
    .attr("r", 7).call(drag).append("title").text((h) => "drag to change " + h.name);
};

Studio.membership.refreshTerms = function () {
  const m = Studio.membership;
  const current = m.current();
  const table = document.getElementById("parameter-table");
  table.replaceChildren();
  if (!current) return;
  const names = current.variable.terms.map((t) => t.name);
  if (!names.includes(m.term)) m.term = names[0] || "";
  Studio.fillSelect(document.getElementById("term-select"), names, m.term);
  const term = current.variable.terms.find((t) => t.name === m.term);
  if (!term) return;
  table.append(Studio.element("tr", {}, [Studio.element("th", { text: "term " + term.name }),
    Studio.element("th", { text: term.family + " (MATLAB " + term.matlab + ")" })]));
  for (const p of term.parameters) {
    const field = Studio.element("input", { type: "number", step: "any", value: String(p.value), "data-parameter": p.name });
    field.disabled = term.type2 || term.family === "linear";
    field.addEventListener("change", () => {
      const value = Number(field.value);
      if (field.value.trim() === "") return;  // being typed
      if (!Number.isFinite(value)) return Studio.message("give " + p.name + " as a number", "bad");
      Studio.membership.setParameter({ variable: current.variable.name, term: term.name, parameter: p.name, value: value });
    });
    const unit = p.role === "slope" ? "per " + (current.variable.unit || "unit") : current.variable.unit;
    table.append(Studio.element("tr", {}, [Studio.element("td", { text: p.name }), Studio.element("td", {}, [field, " " + (unit || "")])]));
  }
  if (term.type2) table.append(Studio.element("tr", {}, [Studio.element("td", { colspan: "2", class: "hint", text: "An interval type-2 term: change its footprint in the text." })]));
};

Studio.on("model", (system) => {
  const m = Studio.membership;
  const names = system.inputs.map((v) => v.name).concat(system.outputs.map((v) => v.name));
  if (!names.includes(m.variable)) m.variable = names[0];
  Studio.fillSelect(document.getElementById("variable-select"),
    system.inputs.map((v) => ({ value: v.name, label: "input " + v.name }))
      .concat(system.outputs.map((v) => ({ value: v.name, label: "output " + v.name }))), m.variable);
  Studio.membership.refreshTerms();
  if (Studio.state.tab === "membership" && m.curvesText !== Studio.editor.getValue()) m.fetch();
});

Studio.on("tab", (tab) => { if (tab === "membership") Studio.membership.fetch(); });

document.addEventListener("DOMContentLoaded", () => {
  document.getElementById("variable-select").addEventListener("change", (event) => {
    Studio.membership.variable = event.target.value;
    Studio.membership.refreshTerms();
    Studio.membership.fetch();
  });
  document.getElementById("term-select").addEventListener("change", (event) => {
    Studio.membership.term = event.target.value;
    Studio.membership.refreshTerms();
    Studio.membership.draw();
  });
});
