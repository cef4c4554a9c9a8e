// Two versions compared (as `fmpc diff`): this edit against the file on disk, or against another file of the folder,
// over a CSV of patients: what differs in the rules, a histogram of each output's change, and the patients whose
// stage changes.
"use strict";

Studio.compare = { csv: null };

Studio.compare.run = Studio.latest(async function () {
  const errors = document.getElementById("compare-errors");
  if (!Studio.system()) {
    errors.replaceChildren(Studio.element("pre", { text: "The text has errors (listed under the editor): fix them first." }));
    return;
  }
  const request = Studio.rulesRequest({ against: document.getElementById("compare-against").value });
  if (Studio.compare.csv) request.csv = { name: Studio.compare.csv.name, text: Studio.compare.csv.text };
  try {
    const answer = await Studio.call("/api/compare", request);
    errors.replaceChildren();
    if (!answer.ok) {
      document.getElementById("compare-results").hidden = true;
      for (const text of answer.errors) errors.append(Studio.element("pre", { text: text }));
      return;
    }
    Studio.compare.show(answer);
  } catch (error) {
    errors.replaceChildren(Studio.element("pre", { text: error.message }));
  }
});

Studio.compare.show = function (answer) {
  document.getElementById("compare-results").hidden = false;
  const list = document.getElementById("compare-differences");
  list.replaceChildren();
  if (!answer.differences.length)
    list.append(Studio.element("li", { class: "none", text: "Nothing: " + answer.second + " defines the same system as " + answer.first + "." }));
  for (const line of answer.differences) list.append(Studio.element("li", { text: line }));
  const box = document.getElementById("compare-outputs");
  box.replaceChildren();
  if (!answer.outputs) {
    box.append(Studio.element("p", { class: "hint", text: "Choose a CSV of patients to see what the differences do to their outputs." }));
    return;
  }
  for (const out of answer.outputs) {
    const section = Studio.element("div", { class: "compare-output", "data-output": out.name });
    section.append(Studio.element("h3", { text: out.name + ": change per patient (" + answer.second + " − " + answer.first + ")" }));
    if (out.agreement) {
      const g = out.agreement;
      // The largest change with its sign, as fmpc diff prints it (a decrease reads as one).
      const largest = out.difference.findIndex((d) => d !== null && Math.abs(d) === g.largest.value);
      section.append(Studio.element("p", { class: "summary", text:
        g.count + " patients; mean |change| " + g.mae.text + "; largest change " +
        Studio.withUnit(Studio.four(out.difference[largest]), out.unit) + " (" + answer.labels[largest] + "); mean change " + g.bias.text +
        "; " + (out.stage_changes.length ? out.stage_changes.length + " patient" + (out.stage_changes.length === 1 ? " changes" : "s change") + " stage"
          : "no patient changes stage") }));
    }
    const svg = document.createElementNS("http://www.w3.org/2000/svg", "svg");
    svg.setAttribute("width", "560");
    svg.setAttribute("height", "260");
    svg.setAttribute("class", "histogram");
    section.append(svg);
    const h = out.histogram;
    if (h.counts.length) {
      const unit = out.unit && out.unit !== "dimensionless" ? " (" + out.unit + ")" : "";
      const f = Studio.frame(svg, [h.lo, h.hi], [0, d3.max(h.counts) * 1.1], "change of " + out.name + unit, "patients", { nice: false });
      const width = (h.hi - h.lo) / h.counts.length;
      h.counts.forEach((count, k) => {
        const x0 = f.x(h.lo + k * width), x1 = f.x(h.lo + (k + 1) * width);
        f.g.append("rect").attr("class", "bin").attr("x", x0 + 1).attr("width", Math.max(x1 - x0 - 2, 1))
          .attr("y", f.y(count)).attr("height", f.height - f.y(count)).append("title").text(count + " patients");
      });
      if (h.lo <= 0 && h.hi >= 0)
        f.g.append("line").attr("class", "zero").attr("x1", f.x(0)).attr("x2", f.x(0)).attr("y1", 0).attr("y2", f.height);
    }
    if (out.stage_changes.length) {
      const table = Studio.element("table", { class: "stage-changes" }, [Studio.element("tr", {},
        ["patient", answer.first, "stage", answer.second, "stage"].map((t) => Studio.element("th", { text: t })))]);
      for (const k of out.stage_changes)
        table.append(Studio.element("tr", {}, [answer.labels[k], Studio.four(out.a[k]), out.stage_a[k] || "(none)",
          Studio.four(out.b[k]), out.stage_b[k] || "(none)"].map((t) => Studio.element("td", { text: t }))));
      section.append(table);
    }
    box.append(section);
  }
  for (const note of answer.notes.concat(answer.warnings)) box.append(Studio.element("p", { class: "hint", text: note }));
};

Studio.compare.fillAgainst = function () {
  const others = Studio.state.files.filter((f) => /\.(fis|fll|fcl)$/.test(f) && f !== Studio.state.path);
  const select = document.getElementById("compare-against");
  Studio.fillSelect(select, [{ value: "", label: "the file on disk (" + Studio.state.path + ")" }].concat(others), select.value);
};

Studio.on("file", () => Studio.compare.fillAgainst());
Studio.on("saved", () => { if (Studio.state.tab === "compare") Studio.compare.run(); });
Studio.on("tab", (tab) => { if (tab === "compare") Studio.compare.run(); });
Studio.on("model", () => { if (Studio.state.tab === "compare") Studio.compare.run(); });

document.addEventListener("DOMContentLoaded", () => {
  Studio.loadCsv(document.getElementById("compare-file"), document.getElementById("compare-folder-file"), (csv) => {
    Studio.compare.csv = csv;
    Studio.compare.run();
  });
  document.getElementById("compare-run").addEventListener("click", () => Studio.compare.run());
  document.getElementById("compare-against").addEventListener("change", () => Studio.compare.run());
});
