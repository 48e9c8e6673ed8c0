// Live charts of the ThermoST panel. The server sends only new rows ([t_ms, v1, v2, ...]); this file keeps
// the buffer per chart, redraws at most once per animation frame, shades controller states, marks alarm
// onsets, pauses and exports the visible window as CSV. Served from the panel itself (no CDN).
window.thermost = (function () {
  const charts = {};
  const STATE_COLOURS = {2: "rgba(76,175,80,0.08)", 4: "rgba(255,193,7,0.12)", 5: "rgba(33,150,243,0.12)",
                         6: "rgba(33,150,243,0.20)", 8: "rgba(244,67,54,0.15)"};

  function setup(id, cfg) {
    // cfg: {columns: [names], series: [column index per series], state: column or -1, alarm: column or -1,
    //       keep_s: buffer length}
    if (!charts[id]) charts[id] = {rows: [], paused: false, pending: false, cfg: cfg, lat: [], draws: 0,
                                   received: 0};
    else charts[id].cfg = cfg;
    return charts[id];
  }

  function instance(id) {
    const el = getElement(id);
    return el && el.chart ? el.chart : null;
  }

  function add(id, rows, history) {
    const c = charts[id];
    if (!c) return;
    const now = Date.now();  // read time -> arrival here (same machine clock as the server)
    for (const r of rows) { c.rows.push(r); if (!history) c.lat.push(now - r[0]); }
    if (!history) c.received += rows.length;
    if (c.lat.length > 5000) c.lat.splice(0, c.lat.length - 5000);
    const keep = c.cfg.keep_s * 1000;
    if (c.rows.length && c.rows[c.rows.length - 1][0] - c.rows[0][0] > keep) {
      const cut = c.rows[c.rows.length - 1][0] - keep;
      let i = 0;
      while (i < c.rows.length && c.rows[i][0] < cut) i++;
      c.rows.splice(0, i);
    }
    if (!c.paused && !c.pending) {
      c.pending = true;
      requestAnimationFrame(() => { c.pending = false; draw(id); });
    }
  }

  function shading(c) {
    const col = c.cfg.state;
    if (col < 0 || !c.rows.length) return [];
    const areas = [];
    let start = c.rows[0][0], state = c.rows[0][col];
    for (const r of c.rows) {
      if (r[col] !== state) {
        if (STATE_COLOURS[state]) areas.push([{xAxis: start, itemStyle: {color: STATE_COLOURS[state]}}, {xAxis: r[0]}]);
        start = r[0]; state = r[col];
      }
    }
    const last = c.rows[c.rows.length - 1][0];
    if (STATE_COLOURS[state]) areas.push([{xAxis: start, itemStyle: {color: STATE_COLOURS[state]}}, {xAxis: last}]);
    return areas;
  }

  function alarmMarks(c) {
    const col = c.cfg.alarm;
    if (col < 0) return [];
    const marks = [];
    let prev = 0;
    for (const r of c.rows) {
      const w = r[col] || 0;
      if (w & ~prev) marks.push({xAxis: r[0], label: {formatter: "alarm " + (w & ~prev).toString(16)}});
      prev = w;
    }
    return marks;
  }

  function draw(id) {
    const c = charts[id], chart = instance(id);
    if (!c || !chart) return;
    const series = c.cfg.series.map((col, k) => {
      const s = {data: c.rows.map((r) => [r[0], r[col]])};
      if (k === 0) {
        s.markArea = {silent: true, data: shading(c)};
        s.markLine = {symbol: "none", lineStyle: {color: "#d32f2f"}, data: alarmMarks(c)};
      }
      return s;
    });
    chart.setOption({series: series});
    c.draws += 1;
  }

  function pause(id, paused) {
    const c = charts[id];
    if (!c) return;
    c.paused = paused;
    if (!paused) draw(id);
  }

  function visible(id) {
    const c = charts[id], chart = instance(id);
    if (!c) return [];
    let lo = -Infinity, hi = Infinity;
    if (chart) {
      const axis = chart.getModel().getComponent("xAxis", 0).axis;
      const ext = axis.scale.getExtent();
      lo = ext[0]; hi = ext[1];
    }
    return c.rows.filter((r) => r[0] >= lo && r[0] <= hi);
  }

  function csv(id, filename) {
    const c = charts[id];
    if (!c) return 0;
    const rows = visible(id);
    const lines = ["time_iso," + c.cfg.columns.slice(1).join(",")];
    for (const r of rows) lines.push(new Date(r[0]).toISOString() + "," + r.slice(1).join(","));
    const blob = new Blob([lines.join("\n") + "\n"], {type: "text/csv"});
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = filename;
    document.body.appendChild(a);
    a.click();
    a.remove();
    return rows.length;
  }

  function count(id) { return charts[id] ? charts[id].rows.length : 0; }

  // figures for `thermost bench`: latencies (ms) since `since` rows were received, redraws, rows
  function stats(id) {
    const c = charts[id];
    return c ? {lat: c.lat.slice(), draws: c.draws, received: c.received} : null;
  }

  return {setup: setup, add: add, pause: pause, csv: csv, count: count, draw: draw, stats: stats};
})();
