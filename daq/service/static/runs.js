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

  /* Under a run with an analysis or a fit: the band analysed and why, the synthesis
   * error, and every caution of the analysis and the fit as a "caution: ..." line. */
  function notesRow(r) {
    const cautions = DAQ.analysisCautions({ cautions: r.cautions }).concat(
      (Array.isArray(r.fit_cautions) ? r.fit_cautions : []).map((t) => "fit: " + t)
    );
    const facts = [DAQ.bandText(r.band), DAQ.synthesisText(r.synthesis_error)].filter(Boolean).join(" · ");
    if (!cautions.length && !facts) return null;
    return el(
      "tr",
      { class: "run-notes-row", dataset: { notesFor: r.run_id } },
      el(
        "td",
        { colspan: "10", class: "run-notes" },
        facts ? el("div", { class: "muted small run-facts" }, facts) : null,
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
          firstThree(r.frequencies_hz, (f, k) =>
            DAQ.withU(fmt.fixed(f, 2), uOf(r.frequencies_u_hz, k), fmt.sig(uOf(r.frequencies_u_hz, k), 1))
          )
        ),
        el(
          "td",
          { class: "num damping" },
          firstThree(r.damping_ratios, (d, k) =>
            DAQ.withU(fmt.pct(d, 2), uOf(r.damping_u, k), fmt.sig(uOf(r.damping_u, k) * 100, 1))
          )
        ),
        el("td", { class: "num psi", title: r.fit ? "fit: " + r.fit : null }, fmt.sig(r.fit_psi, 3))
      );
    }
    cells.push(
      el(
        "td",
        { class: "links" },
        link(runUrl(id, "/report"), "report"),
        " ",
        link(runUrl(id, "/file"), "HDF5", "the sealed run file"),
        " ",
        link(runUrl(id, "/export?format=csv"), "CSV"),
        " ",
        link(runUrl(id, "/export?format=uff"), "UFF")
      )
    );
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
