/* The runs page (runs.html) of `daq serve`: the store's runs, newest first,
 * refreshed from GET /api/runs on load, on every (re)connection of the event
 * stream, and (debounced) when a run is sealed or its analysis or fit ends. */
(function () {
  "use strict";

  const { api, el, $, fmt, events } = window.DAQ;

  let runs = [];
  let loading = false;
  let again = false;

  function runUrl(id, tail) {
    return DAQ.withToken("/api/runs/" + encodeURIComponent(id) + tail);
  }

  function link(href, text, title) {
    return el("a", { href, title: title || null }, text);
  }

  function firstThree(list, format) {
    if (!Array.isArray(list) || !list.length) return "–";
    return list.slice(0, 3).map(format).join(", ");
  }

  /* The k-th standard uncertainty of a list (older services send none). */
  function uOf(list, k) {
    return Array.isArray(list) ? list[k] : null;
  }

  /* A text the service wrote (a string), else `fallback`. */
  function given(text, fallback) {
    return typeof text === "string" && text ? text : fallback;
  }

  /* "analysis failed: <reason>", "fit failed: <reason>" of a run whose stage failed. */
  function failures(r) {
    const out = [];
    for (const stage of ["analysis", "fit"]) {
      if (r[stage] !== "failed") continue;
      const reason = r[stage + "_error"];
      out.push(stage + " failed" + (typeof reason === "string" && reason ? ": " + reason : ""));
    }
    return out;
  }

  /* Under a run with an analysis or a fit: the band analysed and why, the synthesis
   * error, every caution of the analysis and the fit as a "caution: ..." line, and why
   * a stage failed. */
  function notesRow(r) {
    const cautions = DAQ.analysisCautions({ cautions: r.cautions }).concat(
      (Array.isArray(r.fit_cautions) ? r.fit_cautions : []).map((t) => "fit: " + t)
    );
    const facts = [given(r.band_text, DAQ.bandText(r.band)), given(r.synthesis_text, DAQ.synthesisText(r.synthesis_error))]
      .filter(Boolean)
      .join(" · ");
    const failed = failures(r);
    if (!cautions.length && !facts && !failed.length) return null;
    return el(
      "tr",
      { class: "run-notes-row", dataset: { notesFor: r.run_id } },
      el(
        "td",
        { colspan: "10", class: "run-notes" },
        facts ? el("div", { class: "muted small run-facts" }, facts) : null,
        ...failed.map((t) => el("div", { class: "stage-failed" }, t)),
        ...DAQ.cautionLines(cautions, "div")
      )
    );
  }

  /* "20261124T185237.813Z-55e2164e" may break after its date and its time stamp, so that
   * the table fits a 1024 px screen. */
  function idParts(id) {
    const parts = String(id).match(/^(\d{8}T)(.*?-)(.+)$/);
    return parts ? [parts[1], el("wbr"), parts[2], el("wbr"), parts[3]] : [String(id)];
  }

  function newestFirst(a, b) {
    const ta = Date.parse(a.start_time);
    const tb = Date.parse(b.start_time);
    const va = Number.isNaN(ta) ? -Infinity : ta;
    const vb = Number.isNaN(tb) ? -Infinity : tb;
    if (va !== vb) return vb - va;
    return String(b.run_id).localeCompare(String(a.run_id));
  }

  /* The default fit's Psi with its unit ("0.3875 m/s²"), or "failed" (its reason in the
   * tooltip and in a line under the run), or "–" while there is none. */
  function psiCell(r) {
    if (r.fit === "failed") {
      return el("td", { class: "num psi psi-failed", title: given(r.fit_error, "the fit failed") }, "failed");
    }
    const text = given(r.fit_psi_text, fmt.sig(r.fit_psi, 4));
    return el("td", { class: "num psi", title: r.fit ? "fit: " + r.fit : null }, text);
  }

  function row(r) {
    const id = r.run_id;
    const analysis = r.analysis || "none";
    const cells = [
      el(
        "td",
        {
          class: "run-id",
          title: [r.operator ? "operator: " + r.operator : "", r.note ? "note: " + r.note : ""].filter(Boolean).join("\n") || null,
        },
        ...idParts(id)
      ),
      el("td", { class: "time" }, fmt.time(r.start_time)),
      el("td", null, r.kind || "–"),
      el("td", { class: r.complete ? "complete" : "incomplete" }, r.complete ? "complete" : "incomplete"),
      el("td", { class: "num" }, (r.n_accepted ?? "–") + "/" + (r.n_hits ?? "–")),
      el("td", { class: "analysis-state state-" + analysis, title: r.fit ? "fit: " + r.fit : null }, analysis),
    ];
    if (r.error) {
      cells.push(el("td", { class: "run-error", colspan: "3" }, r.error));
    } else {
      cells.push(
        el(
          "td",
          { class: "num frequencies" },
          Array.isArray(r.frequencies_text)
            ? firstThree(r.frequencies_text, String)
            : firstThree(r.frequencies_hz, (f, k) => DAQ.measured(f, uOf(r.frequencies_u_hz, k), fmt.fixed(f, 4)))
        ),
        el(
          "td",
          { class: "num damping" },
          Array.isArray(r.damping_text)
            ? firstThree(r.damping_text, String)
            : firstThree(r.damping_ratios, (d, k) =>
                DAQ.measured(d * 100, Number.isFinite(uOf(r.damping_u, k)) ? uOf(r.damping_u, k) * 100 : null, fmt.sig(d * 100, 3))
              )
        ),
        psiCell(r)
      );
    }
    const exports = Array.isArray(r.exports) ? r.exports : ["csv", "uff"];
    const files = [link(runUrl(id, "/report"), "report"), link(runUrl(id, "/file"), "HDF5", "the sealed run file")];
    // Only the formats the run can be written as: CSV holds time records, which a run of
    // FRFs only (an import of UFF or FRF text) has none of.
    if (exports.includes("csv")) files.push(link(runUrl(id, "/export?format=csv"), "CSV", "the time records as text"));
    if (exports.includes("uff")) files.push(link(runUrl(id, "/export?format=uff"), "UFF", "the FRFs as UFF 58"));
    cells.push(el("td", { class: "links" }, ...files.flatMap((a, i) => (i ? [" ", a] : [a]))));
    // labels for the stacked layout on narrow screens (style.css)
    const labels = ["Run", "Started", "Kind", "Complete", "Accepted", "Analysis"].concat(
      r.error ? ["Error"] : ["Frequencies (Hz)", "Damping (%)", "Fit Psi"],
      ["Files"]
    );
    cells.forEach((c, i) => c.setAttribute("data-label", labels[i]));
    const main = el("tr", { dataset: { runId: id }, class: r.error ? "damaged" : null }, ...cells);
    const notes = r.error ? null : notesRow(r);
    return notes ? [main, notes] : [main];
  }

  function render() {
    const body = $("runs-table").tBodies[0];
    const sorted = [...runs].sort(newestFirst);
    if (!sorted.length) {
      body.replaceChildren(el("tr", { class: "empty-row" }, el("td", { colspan: "10" }, "No runs in the store yet.")));
    } else {
      body.replaceChildren(...sorted.flatMap(row));
    }
    const damaged = sorted.filter((r) => r.error).length;
    $("runs-summary").textContent =
      fmt.plural(sorted.length, "run", "runs") + (damaged ? ", " + damaged + " damaged" : "");
  }

  async function load() {
    if (loading) {
      again = true;
      return;
    }
    loading = true;
    try {
      do {
        again = false;
        try {
          const list = await api("GET", "/api/runs");
          runs = Array.isArray(list) ? list : [];
          render();
        } catch (e) {
          /* #error or the token panel says why */
        }
      } while (again);
    } finally {
      loading = false;
    }
  }

  let timer = null;
  function refreshSoon() {
    clearTimeout(timer);
    timer = setTimeout(load, 300);
  }

  for (const type of ["run_sealed", "analysis_started", "analysis_done", "analysis_failed", "fit_done", "fit_failed"]) {
    events.on(type, refreshSoon);
  }
  events.onHello(refreshSoon);
  DAQ.onToken(() => render()); // the links carry the token

  $("refresh").addEventListener("click", load);

  load();
  events.start();
})();
