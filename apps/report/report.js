// skerry report: draws the page from the JSON block 'skerry-data' with Chart.js 3.
// After drawing, every chart canvas gets data-painted = number of saturated (data-coloured)
// pixels inside its plot area, and <body> gets data-charts-drawn / data-charts-painted, so a
// headless browser can check that the plots were really drawn (tests/apps/test_report.cc).
(function () {
  'use strict';
  const data = JSON.parse(document.getElementById('skerry-data').textContent);
  const PALETTE = ['#0b5cad', '#d1495b', '#2a9d8f', '#e09f3e', '#7b2cbf', '#3d5a80', '#9c6644',
    '#43aa8b'];

  Chart.defaults.animation = false;
  Chart.defaults.maintainAspectRatio = false;
  Chart.defaults.font.family = '"DejaVu Sans", Helvetica, Arial, sans-serif';
  Chart.defaults.font.size = 12;
  Chart.defaults.elements.point.radius = 0;
  Chart.defaults.elements.line.borderWidth = 1.5;
  Chart.defaults.plugins.legend.labels.boxWidth = 14;
  Chart.defaults.plugins.tooltip.enabled = true;

  // One colour per configuration / run label, the same in every chart and table.
  const labels = [];
  for (const run of data.runs) if (!labels.includes(run.label)) labels.push(run.label);
  for (const cmp of data.comparisons) {
    for (const c of (cmp.table && cmp.table.configs) || []) if (!labels.includes(c)) labels.push(c);
  }
  const color = (label) => PALETTE[Math.max(0, labels.indexOf(label)) % PALETTE.length];
  const rgba = (hex, a) => {
    const v = parseInt(hex.slice(1), 16);
    return `rgba(${(v >> 16) & 255},${(v >> 8) & 255},${v & 255},${a})`;
  };
  const fmt = (v, digits) => (typeof v === 'number' && isFinite(v) ? v.toFixed(digits) : '–');
  const xy = (t, v, floor) => t.map((x, i) => ({
    x, y: v[i] === null || v[i] === undefined ? null : (floor ? Math.max(floor, v[i]) : v[i])
  }));

  function el(tag, cls, text) {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  }

  const charts = [];
  function panel(parent, title, note, boxClass) {
    const p = el('div', 'panel');
    p.appendChild(el('h3', '', title));
    const box = el('div', 'chart-box' + (boxClass ? ' ' + boxClass : ''));
    const canvas = el('canvas');
    canvas.setAttribute('data-chart', title);
    box.appendChild(canvas);
    p.appendChild(box);
    if (note) p.appendChild(el('p', 'note', note));
    parent.appendChild(p);
    return canvas;
  }
  function chart(canvas, config) {
    const c = new Chart(canvas.getContext('2d'), config);
    charts.push(c);
    return c;
  }

  // GNSS outages and jumps shaded in time plots (options.plugins.spans.spans).
  Chart.register({
    id: 'spans',
    beforeDatasetsDraw(c, args, opts) {
      const spans = (opts && opts.spans) || [];
      if (!spans.length || !c.scales.x) return;
      const a = c.chartArea, x = c.scales.x, ctx = c.ctx;
      ctx.save();
      for (const s of spans) {
        const x0 = Math.max(a.left, x.getPixelForValue(s.t0));
        const x1 = Math.min(a.right, x.getPixelForValue(s.t1));
        if (!(x1 > x0)) continue;
        ctx.fillStyle = s.type === 'outage' ? 'rgba(120,130,140,0.16)' : 'rgba(224,159,62,0.20)';
        ctx.fillRect(x0, a.top, x1 - x0, a.bottom - a.top);
        ctx.fillStyle = '#5f6b7a';
        ctx.font = '11px "DejaVu Sans", sans-serif';
        ctx.fillText(s.type === 'outage' ? 'GNSS outage' : 'GNSS jump', x0 + 4, a.top + 13);
      }
      ctx.restore();
    }
  });

  // Box-plot whiskers and medians over floating bars (options.plugins.boxes.stats[i]).
  Chart.register({
    id: 'boxes',
    afterDatasetsDraw(c, args, opts) {
      const stats = (opts && opts.stats) || [];
      if (!stats.length) return;
      const meta = c.getDatasetMeta(0), y = c.scales.y, ctx = c.ctx;
      ctx.save();
      stats.forEach((s, i) => {
        const bar = meta.data[i];
        if (!bar || !s) return;
        const half = bar.width / 2, x = bar.x;
        ctx.strokeStyle = s.color;
        ctx.lineWidth = 2;
        ctx.beginPath();
        ctx.moveTo(x - half, y.getPixelForValue(s.median));
        ctx.lineTo(x + half, y.getPixelForValue(s.median));
        ctx.stroke();
        ctx.lineWidth = 1.2;
        for (const [from, to] of [[s.q3, s.max], [s.q1, s.min]]) {
          ctx.beginPath();
          ctx.moveTo(x, y.getPixelForValue(from));
          ctx.lineTo(x, y.getPixelForValue(to));
          ctx.moveTo(x - half / 2, y.getPixelForValue(to));
          ctx.lineTo(x + half / 2, y.getPixelForValue(to));
          ctx.stroke();
        }
      });
      ctx.restore();
    }
  });

  const timeAxis = { type: 'linear', title: { display: true, text: 'time (s)' } };
  const spansOf = (run) => run.events || [];

  // ------------------------------------------------------------------ header and cards
  const subtitle = [];
  if (data.comparisons.length) {
    for (const cmp of data.comparisons) {
      subtitle.push(`comparison of ${(cmp.table.configs || []).length} configurations on ` +
        `${(cmp.table.datasets || []).join(', ')} over ${(cmp.table.seeds || []).length} seed(s)`);
    }
  }
  for (const tw of data.twins || []) {
    subtitle.push(`digital twin of ${(tw.yaml && tw.yaml.twin && tw.yaml.twin.recording) || tw.folder}`);
  }
  if (data.runs.length) subtitle.push(`${data.runs.length} run(s): ` +
    data.runs.map((r) => r.label).join(', '));
  subtitle.push(`generated ${data.generated}`);
  document.getElementById('subtitle').textContent = subtitle.join(' · ');

  const cards = document.getElementById('cards');
  for (const run of data.runs) {
    const card = el('div', 'card');
    card.style.borderTopColor = color(run.label);
    card.appendChild(el('div', 'name', run.label));
    const acc = run.summary && run.summary.accuracy;
    const figs = [['dataset', run.dataset || '–'], ['configuration', run.config]];
    if (acc) {
      figs.push(['horizontal RMSE', fmt(acc.horizontal_m.rmse, 3) + ' m']);
      figs.push(['heading RMSE', fmt(acc.heading_deg.rmse, 3) + '°']);
      if (acc.nees) {
        figs.push(['position ANEES', `${fmt(acc.nees.anees_position, 2)} [${
          fmt(acc.nees.anees_position_bounds_95[0], 2)}, ${fmt(acc.nees.anees_position_bounds_95[1], 2)}]`]);
      }
      if (acc.events) {
        figs.push(['RMSE outside outages', fmt(acc.events.horizontal_outside_outages_m.rmse, 3) + ' m']);
        for (const o of acc.events.outages) {
          figs.push([`error after ${fmt(o.duration_s, 0)} s outage`, fmt(o.horizontal_error_at_end_m, 2) + ' m']);
        }
        for (const j of acc.events.jumps) {
          figs.push([`max error, ${fmt(j.offset_m, 1)} m jump`, fmt(j.max_horizontal_error_m, 2) + ' m']);
        }
      }
    }
    const timing = run.summary && run.summary.timing;
    if (timing && timing.realtime_factor) figs.push(['speed', fmt(timing.realtime_factor, 0) + '× real time']);
    // Sensors beyond IMU and GNSS (a camera's skyline, pose fixes...): blocks the window took,
    // rejected, re-acquired on; frames the frontend skipped and its time per frame.
    const sensors = (run.summary && run.summary.sensors) || {};
    for (const name of Object.keys(sensors)) {
      const s = sensors[name];
      let v = `${s.accepted} used, ${s.rejected_by_gate} gated, ${s.dropped} dropped`;
      if (s.reacquired) v += `, ${s.reacquired} re-acquired`;
      const f = s.frontend;
      if (f && typeof f.frames === 'number') {
        v += ` of ${f.frames} frames`;
        const skipped = (f.skipped_no_sky || 0) + (f.skipped_few_samples || 0);
        if (skipped) v += ` (${skipped} skipped)`;
        if (typeof f.extraction_ms_per_frame === 'number') v += `, ${fmt(f.extraction_ms_per_frame, 1)} ms/frame`;
      }
      figs.push([`sensor ${name}`, v]);
    }
    for (const [k, v] of figs) {
      const f = el('div', 'fig');
      f.appendChild(el('span', '', k));
      f.appendChild(el('b', '', v));
      card.appendChild(f);
    }
    cards.appendChild(card);
  }

  // ------------------------------------------------------------------ comparison
  const comparison = document.getElementById('comparison');
  function quartiles(values) {
    // Linear interpolation between closest ranks (Hyndman & Fan type 7, as numpy and R).
    const v = values.filter((x) => typeof x === 'number' && isFinite(x)).sort((a, b) => a - b);
    if (!v.length) return null;
    const q = (p) => {
      const h = (v.length - 1) * p, lo = Math.floor(h), hi = Math.ceil(h);
      return v[lo] + (h - lo) * (v[hi] - v[lo]);
    };
    return { min: v[0], q1: q(0.25), median: q(0.5), q3: q(0.75), max: v[v.length - 1] };
  }

  for (const cmp of data.comparisons) {
    const t = cmp.table;
    if (!t || !t.rows) continue;
    comparison.appendChild(el('h2', '', `Comparison (reference: ${t.reference_config})`));
    // The table.
    const wrap = el('div', 'table-wrap');
    const table = el('table', 'results');
    const cols = [
      ['dataset', (r) => r.dataset], ['runs', (r) => `${r.runs - r.failed_runs}/${r.runs}`],
      ['hor. RMSE m', (r) => fmt(r.horizontal_rmse_m, 3)], ['hor. max m', (r) => fmt(r.horizontal_max_m, 2)],
      ['RMSE outside outages m', (r) => fmt(r.horizontal_rmse_outside_outages_m, 3)],
      ['outage end m (median)', (r) => fmt(r.outage_end_error_m && r.outage_end_error_m.median, 2)],
      ['jump max m', (r) => fmt(r.jump_max_error_m, 2)],
      ['heading RMSE °', (r) => fmt(r.heading_rmse_deg, 3)], ['heading max °', (r) => fmt(r.heading_max_deg, 2)],
      ['RPE 1 s m', (r) => fmt(r.rpe_translation_m, 3)],
      ['ANEES [95%]', (r) => r.anees_position === null ? '–' :
        `${fmt(r.anees_position, 2)} [${fmt(r.anees_bounds_95[0], 2)}, ${fmt(r.anees_bounds_95[1], 2)}]`],
      ['epochs inside 95%', (r) => typeof r.nees_inside_95 === 'number' ? fmt(100 * r.nees_inside_95, 1) + ' %' : '–'],
      ['consistency', (r) => r.consistency],
      ['update ms med/p95/max', (r) => `${fmt(r.update_ms.median, 2)} / ${fmt(r.update_ms.p95, 2)} / ${fmt(r.update_ms.max, 1)}`],
      ['iterations', (r) => fmt(r.iterations.mean, 1)], ['solve failures', (r) => String(r.solve_failures)],
      ['valid epochs', (r) => fmt(100 * r.share_valid, 1) + ' %'],
      ['AHED pos', (r) => r.ahed ? fmt(r.ahed.position, 3) : 'ref'],
      ['AHED hdg', (r) => r.ahed ? fmt(r.ahed.heading, 3) : 'ref'],
      ['AHED vel', (r) => r.ahed ? fmt(r.ahed.velocity, 3) : 'ref'],
      ['AHED bias', (r) => r.ahed ? fmt(r.ahed.biases, 3) : 'ref'],
      ['AHED full', (r) => r.ahed ? fmt(r.ahed.full, 3) : 'ref'],
      ['one valid', (r) => r.share_one_valid === null ? 'ref' : fmt(100 * r.share_one_valid, 1) + ' %'],
    ];
    const head = el('tr');
    head.appendChild(el('th', '', 'configuration'));
    for (const [name] of cols) head.appendChild(el('th', '', name));
    table.appendChild(head);
    for (const r of t.rows) {
      const tr = el('tr', r.reference ? 'reference' : '');
      const first = el('td');
      const sw = el('span', 'swatch');
      sw.style.background = color(r.config);
      first.appendChild(sw);
      first.appendChild(document.createTextNode(r.config + (r.reference ? ' (reference)' : '')));
      tr.appendChild(first);
      for (const [name, f] of cols) {
        const td = el('td', name === 'consistency' ? r.consistency : '', f(r));
        tr.appendChild(td);
      }
      table.appendChild(tr);
    }
    wrap.appendChild(table);
    comparison.appendChild(wrap);
    comparison.appendChild(el('p', 'note',
      'Pooled over all epochs of all seeds. Consistency: at each epoch the NEES averaged over the seeds ' +
      'should lie inside its 95% chi-square bounds; consistent when at least 90% of epochs do, else ' +
      'overconfident (mostly above: covariance too small) or underconfident (mostly below). The pooled ' +
      'ANEES bounds count each run\'s epochs as the independent samples they are worth (effective sample ' +
      'size: consecutive keyframes are correlated). AHED: average Hellinger distance to ' +
      'the reference configuration\'s run of the same data and seed, per state block (0 = same ' +
      'estimates and covariances, 1 = disjoint).'));

    // Bars per configuration.
    const dataset0 = t.datasets[0];
    const rows = t.rows.filter((r) => r.dataset === dataset0);
    const names = rows.map((r) => r.config);
    const barGrid = el('div', 'grid narrow');
    comparison.appendChild(el('h2', '', `Per configuration (${dataset0})`));
    comparison.appendChild(barGrid);
    const bar = (title, values, unit, extra, note, log) => {
      if (!values.some((v) => typeof v === 'number')) return;  // e.g. no ground truth
      const datasets = [{
        type: 'bar', label: title, data: values,
        backgroundColor: names.map((n) => rgba(color(n), 0.75)), borderColor: names.map(color), borderWidth: 1
      }].concat(extra || []);
      chart(panel(barGrid, title, note), {
        type: 'bar', data: { labels: names, datasets },
        options: {
          plugins: { legend: { display: !!(extra && extra.length) } },
          scales: { y: log ? { type: 'logarithmic', title: { display: true, text: unit } }
            : { beginAtZero: true, title: { display: true, text: unit } } }
        }
      });
    };
    bar('horizontal RMSE', rows.map((r) => r.horizontal_rmse_m), 'm');
    bar('heading RMSE', rows.map((r) => r.heading_rmse_deg), 'deg');
    const lo = rows.map((r) => r.anees_bounds_95 ? r.anees_bounds_95[0] : null);
    const hi = rows.map((r) => r.anees_bounds_95 ? r.anees_bounds_95[1] : null);
    bar('position ANEES', rows.map((r) => r.anees_position), 'ANEES (ideal 3)', [
      { type: 'line', label: '95% lower bound', data: lo, borderColor: '#1a7f37', borderDash: [5, 4], pointRadius: 3 },
      { type: 'line', label: '95% upper bound', data: hi, borderColor: '#c0392b', borderDash: [5, 4], pointRadius: 3 }
    ], 'Log scale: an overconfident configuration can be 100 times the others. Pooled bounds for the ' +
      'effective number of independent epochs; the table\'s consistency uses the per-epoch test.', true);
    bar('median update time', rows.map((r) => r.update_ms.median), 'ms', [
      { type: 'line', label: 'p95', data: rows.map((r) => r.update_ms.p95), borderColor: '#5f6b7a', borderDash: [4, 3], pointRadius: 3, showLine: false }
    ]);

    // Box plots over seeds.
    const boxGrid = el('div', 'grid narrow');
    comparison.appendChild(el('h2', '', 'Spread over seeds'));
    comparison.appendChild(boxGrid);
    const box = (title, key, unit) => {
      const stats = rows.map((r) => {
        const q = quartiles(r.per_run.map((p) => p[key]));
        return q ? Object.assign(q, { color: color(r.config) }) : null;
      });
      if (!stats.some(Boolean)) return;  // no ground truth: nothing to spread
      const points = [];
      rows.forEach((r) => r.per_run.forEach((p) => {
        if (typeof p[key] === 'number') points.push({ x: r.config, y: p[key] });
      }));
      chart(panel(boxGrid, title + ' per seed', 'Box: quartiles (linear interpolation, type 7); ' +
        'line: median; whiskers: min and max; dots: one per seed.'), {
        type: 'bar',
        data: {
          labels: names,
          datasets: [
            { type: 'bar', label: 'quartiles', data: stats.map((s) => s ? [s.q1, s.q3] : null),
              backgroundColor: names.map((n) => rgba(color(n), 0.35)), borderColor: names.map(color),
              borderWidth: 1.5, barPercentage: 0.5, borderSkipped: false },
            { type: 'scatter', label: 'seeds', data: points, pointRadius: 3,
              backgroundColor: points.map((p) => rgba(color(p.x), 0.9)) }
          ]
        },
        options: {
          plugins: { legend: { display: false }, boxes: { stats } },
          scales: {
            y: { beginAtZero: true, suggestedMax: Math.max(...stats.filter(Boolean).map((s) => s.max)) * 1.05,
              title: { display: true, text: unit } }
          }
        }
      });
    };
    box('horizontal RMSE', 'horizontal_rmse_m', 'm');
    box('heading RMSE', 'heading_rmse_deg', 'deg');

    // Hellinger distance over time.
    if (cmp.hed && cmp.hed.length) {
      const hedGrid = el('div', 'grid narrow');
      comparison.appendChild(el('h2', '',
        `Hellinger distance to ${t.reference_config} over time (${cmp.dataset}, seed ${cmp.seed})`));
      comparison.appendChild(hedGrid);
      const spans = (data.runs.find((r) => r.dataset === cmp.dataset) || {}).events || [];
      for (const block of ['position', 'heading', 'velocity', 'biases']) {
        chart(panel(hedGrid, `HED, ${block}`), {
          type: 'line',
          data: {
            datasets: cmp.hed.map((h) => ({
              label: h.config, data: xy(h.t, h[block]), borderColor: color(h.config), spanGaps: false
            }))
          },
          options: {
            plugins: { spans: { spans } },
            scales: { x: timeAxis, y: { min: 0, max: 1, title: { display: true, text: 'HED' } } }
          }
        });
      }
    }
  }

  // ------------------------------------------------------------------ digital twin
  // A twin folder (skerry twin, docs/twin.md): the fidelity test against its floor, before and
  // after calibration, the GNSS statistics of a log without IMU, and the models side by side.
  const twinSection = document.getElementById('twin');
  const num = (v) => (typeof v === 'number' && isFinite(v) ? v : null);
  // Significant digits, no trailing zeros: 0.000283, 3.49e-6, 18.22.
  const sig = (v, digits) => {
    const x = num(v);
    return x === null ? '–' : String(Number(x.toPrecision(digits || 4)));
  };
  function table(parent, head, rows, cls) {
    const wrap = el('div', 'table-wrap');
    const t = el('table', 'results');
    const tr = el('tr');
    for (const h of head) tr.appendChild(el('th', '', h));
    t.appendChild(tr);
    for (const r of rows) {
      const row = el('tr', (cls && cls(r)) || '');
      for (const c of r.cells) {
        const td = el('td', (c && c.cls) || '', c && typeof c === 'object' ? c.text : c);
        row.appendChild(td);
      }
      t.appendChild(row);
    }
    wrap.appendChild(t);
    parent.appendChild(wrap);
  }
  const verdict = (ok) => ({ text: ok ? 'indistinguishable' : 'twin differs', cls: ok ? 'consistent' : 'overconfident' });

  for (const tw of data.twins || []) {
    const y = tw.yaml || {};
    const p = y.twin || {};
    twinSection.appendChild(el('h2', '', `Digital twin of ${p.recording || tw.folder}`));
    const facts = [`truth: ${p.truth || '–'} (${p.truth_keyframes || '–'} keyframes)`,
      `estimator configuration: ${p.config || '–'}`, `model: ${p.model_source || '–'}`, `seed ${p.seed}`];
    if (y.calibration) {
      facts.push(`calibration: objective ${sig(y.calibration.objective_before, 3)} → ` +
        `${sig(y.calibration.objective_after, 3)} in ${y.calibration.evaluations} evaluations`);
      const h = y.calibration.held_out;
      if (h) {
        facts.push(`on ${h.twins} held-out twins ${sig(h.objective_identified, 3)} (identified) against ` +
          `${sig(h.objective_calibrated, 3)} (calibrated): ` +
          (h.calibrated_kept ? 'the calibrated model is kept' : 'the calibration did not hold, the identified model is kept'));
      }
    }
    twinSection.appendChild(el('p', 'note', facts.join(' · ')));

    // The test per block: the recording's distance to its twins beside the twins' own spread.
    const tests = [];
    const calibrated = y.calibration && !(y.calibration.held_out && !y.calibration.held_out.calibrated_kept);
    if (y.fidelity) tests.push([calibrated ? 'calibrated model' : 'the twin\'s model', y.fidelity]);
    if (y.fidelity_identified_model) tests.push(['identified model', y.fidelity_identified_model]);
    // The blocks in twin.yaml's order (the page's JSON sorts keys), then any other.
    const order = ['position', 'heading', 'attitude', 'velocity', 'biases', 'full'];
    const present = tests.length ? Object.keys(tests[0][1].blocks || {}) : [];
    const blockNames = order.filter((b) => present.includes(b)).concat(present.filter((b) => !order.includes(b)));
    for (const [name, f] of tests) {
      twinSection.appendChild(el('h3', '', `Fidelity, ${name}: the recording among ${f.twins} twins ` +
        `(two-sided rank test at α = ${sig(f.alpha, 2)}${f.twins_left_out ? `; the estimator gave up on ${f.twins_left_out} twin(s), replaced by further seeds` : ''})`));
      table(twinSection, ['block', 'real vs twin AHED', 'from the means', 'from the covariances',
        'twin vs twin AHED', 'twin vs twin sd', 'twin vs twin max', 'floor (closed form)', 'z', 'p', 'verdict'],
      blockNames.map((b) => {
        const x = f.blocks[b];
        return { cells: [b, fmt(x.real_vs_twin_ahed, 3), fmt(x.real_vs_twin_meandiff, 3), fmt(x.real_vs_twin_covdiff, 3),
          fmt(x.twin_vs_twin_ahed, 3), fmt(x.twin_vs_twin_sd, 3), fmt(x.twin_vs_twin_max, 3), fmt(x.floor, 3),
          fmt(x.z, 2), fmt(x.p_value, 2), verdict(x.indistinguishable)] };
      }));
    }
    if (tests.length) {
      twinSection.appendChild(el('p', 'note',
        'AHED: average Hellinger distance between the window\'s Gaussian estimates over time, per state block ' +
        '(0 = the same, 1 = disjoint), split into the part from the means and the part from the covariances. ' +
        'Twin vs twin: the same distance between twins of different seeds, the floor any perfect twin scores; ' +
        'floor (closed form): two independent noise realisations through a consistent estimator, ' +
        'E[H²] = 1 − 1.5^(−k/2) for a k-dimensional block. Indistinguishable when the recording\'s rank among ' +
        'all runs by mean distance to the others is not extreme at α (two-sided); z: its distance in twin-vs-twin sds.'));
      const grid = el('div', 'grid narrow');
      twinSection.appendChild(grid);
      const sets = tests.map(([name, f], i) => ({
        type: 'bar', label: `real vs twin (${name})`, data: blockNames.map((b) => num(f.blocks[b].real_vs_twin_ahed)),
        backgroundColor: rgba(PALETTE[(i + 1) % PALETTE.length], 0.75), borderColor: PALETTE[(i + 1) % PALETTE.length], borderWidth: 1
      }));
      const f0 = tests[0][1];
      sets.push({ type: 'bar', label: 'twin vs twin (mean)', data: blockNames.map((b) => num(f0.blocks[b].twin_vs_twin_ahed)),
        backgroundColor: rgba('#5f6b7a', 0.55), borderColor: '#5f6b7a', borderWidth: 1 });
      sets.push({ type: 'line', label: 'twin vs twin max', data: blockNames.map((b) => num(f0.blocks[b].twin_vs_twin_max)),
        borderColor: '#1d2733', borderDash: [5, 4], pointRadius: 4, showLine: false, pointStyle: 'line' });
      sets.push({ type: 'line', label: 'floor (closed form)', data: blockNames.map((b) => num(f0.blocks[b].floor)),
        borderColor: '#1a7f37', pointRadius: 4, showLine: false, pointStyle: 'rectRot', backgroundColor: '#1a7f37' });
      chart(panel(grid, 'Real vs twin against twin vs twin, per block',
        'A twin like the recording puts the coloured bars among the grey (the twins\' spread up to the dashed mark).'), {
        type: 'bar', data: { labels: blockNames, datasets: sets },
        options: { scales: { y: { min: 0, max: 1, title: { display: true, text: 'AHED' } } } }
      });
      const ot = tw.over_time;
      if (ot && ot.t && ot.t.length) {
        const blocks = blockNames.filter((b) => ot[b]);
        chart(panel(grid, 'Hellinger distance, recording vs twins, over time',
          'At each epoch the mean over the twins of the recording\'s Hellinger distance to each twin.'), {
          type: 'line',
          data: { datasets: blocks.map((b, i) => ({ label: b, data: xy(ot.t, ot[b]), borderColor: PALETTE[i % PALETTE.length], borderWidth: 1, spanGaps: false })) },
          options: { scales: { x: timeAxis, y: { min: 0, max: 1, title: { display: true, text: 'HED' } } } }
        });
      }
    }

    // A log without IMU: statistics of its fixes.
    const stats = [];
    if (y.gnss_statistics) stats.push([y.calibration ? 'calibrated model' : 'the twin\'s model', y.gnss_statistics]);
    if (y.gnss_statistics_identified_model) stats.push(['identified model', y.gnss_statistics_identified_model]);
    for (const [name, list] of stats) {
      twinSection.appendChild(el('h3', '', `GNSS statistics, ${name}: the recording among its twins`));
      table(twinSection, ['statistic', 'recording', 'twins mean', 'twins sd', 'twins min', 'twins max', 'p', 'verdict'],
        list.map((s) => ({ cells: [s.statistic, sig(s.real), sig(s.twins_mean), sig(s.twins_sd, 2), sig(s.twins_min),
          sig(s.twins_max), fmt(s.p_value, 2), verdict(s.indistinguishable)] })));
    }

    // The models: what was identified (with its uncertainty), the sensor sheet, what the twin used.
    const rows = [];
    const model = y.model || {}, idModel = y.identified_model || null;
    const sheet = (y.imu && y.imu.dataset_yaml) || {};
    const used = new Set();
    const isId = (v) => v && typeof v === 'object' && 'value' in v && 'sigma' in v;
    const add = (section, key, v, modelKey) => {
      const mk = modelKey === undefined ? key : modelKey;
      const m = model[section] && num(model[section][mk]);
      const im = idModel && idModel[section] ? num(idModel[section][mk]) : null;
      if (m !== null && m !== undefined) used.add(`${section}.${mk}`);
      rows.push({ cells: [`${section}.${key}`, `${sig(v.value)} ± ${sig(v.sigma, 2)}`,
        v.identified ? 'yes' : { text: 'no', cls: 'underconfident' }, sig(sheet[key]),
        m === null || m === undefined ? '–' : sig(m),
        im !== null && m !== null && m !== undefined && Math.abs(im - m) > 1e-12 * Math.max(1, Math.abs(m)) ? `from ${sig(im)}` : ''] });
    };
    for (const section of ['imu', 'gnss']) {
      const s = y[section] || {};
      for (const key of Object.keys(s)) if (isId(s[key])) add(section, key, s[key]);
      // Nested groups and the model keys their values set (null: none).
      const groups = {
        gross_errors: (k) => `gross_${k}`,
        solve_pattern: (k) => (k.startsWith('propagation_') ? k : k.startsWith('white_') ? null : `solve_${k}`)
      };
      for (const [group, keyOf] of Object.entries(groups)) {
        const g = s[group] || {};
        for (const key of Object.keys(g)) if (isId(g[key])) add(section, `${group}.${key}`, g[key], keyOf(key));
      }
    }
    for (const section of Object.keys(model)) {
      if (!y[section]) continue;  // a log without IMU: its twin has no IMU model to show
      for (const key of Object.keys(model[section])) {
        if (used.has(`${section}.${key}`)) continue;
        const m = num(model[section][key]);
        const im = idModel && idModel[section] ? num(idModel[section][key]) : null;
        rows.push({ cells: [`${section}.${key}`, '–', '–', sig(sheet[key]), sig(m),
          im !== null && m !== null && Math.abs(im - m) > 1e-12 * Math.max(1, Math.abs(m)) ? `from ${sig(im)}` : ''] });
      }
    }
    if (rows.length) {
      twinSection.appendChild(el('h3', '', 'Sensor models: identified, on the sheet, in the twin'));
      table(twinSection, ['parameter', 'identified ± σ', 'identified', 'dataset.yaml (sheet)', 'twin model', 'calibration'], rows);
      twinSection.appendChild(el('p', 'note',
        'Identified: from the recording (Allan deviation at rest or residuals against the batch truth; GNSS ' +
        'from the fixes\' residuals), σ from a moving-block bootstrap; "no": the data could not show it, the ' +
        'value is what the twin assumes. Calibration: the value the search moved from. Units in the names.'));
    }
    const probes = (y.gnss && y.gnss.drift_detection) || [];
    if (probes.length) {
      twinSection.appendChild(el('h3', '', 'GNSS drift: what the batch truth leaves visible'));
      table(twinSection, ['correlation time s', 'survives the batch h / v', 'seen from h / v m (gain)',
        'not seen up to h / v m (identification)'],
      probes.map((d) => ({ cells: [sig(d.tau_s, 3),
        `${fmt(100 * d.batch_gain_horizontal, 0)} % / ${fmt(100 * d.batch_gain_vertical, 0)} %`,
        `${sig(d.gain_limit_sigma_horizontal_m, 3)} / ${sig(d.gain_limit_sigma_vertical_m, 3)}`,
        `${sig(d.detectable_sigma_horizontal_m, 3)}${d.confirmed_horizontal ? '' : '+'} / ` +
        `${sig(d.detectable_sigma_vertical_m, 3)}${d.confirmed_vertical ? '' : '+'}`] })));
      twinSection.appendChild(el('p', 'note',
        'A known drift added to the fixes and the batch re-run: the share of it left in the residuals, the ' +
        'smallest drift that share would show, and the smallest the identification was seen to find ' +
        '(+: not found even there). An unidentified drift\'s σ in the models table is the largest of the last column.'));
    }
    const timing = y.timing || {};
    const streams = Object.keys(timing);
    if (streams.length) {
      twinSection.appendChild(el('h3', '', 'Streams: rates, jitter, gaps (from the time stamps)'));
      table(twinSection, ['stream', 'samples', 'duration s', 'rate Hz', 'jitter s', 'gaps', 'longest gap s', 'dropped'],
        streams.map((k) => {
          const s = timing[k];
          return { cells: [k, String(s.samples), fmt(s.duration_s, 1), sig(s.rate_hz), sig(s.period_jitter_s, 2),
            String(s.gaps), fmt(s.longest_gap_s, 3), fmt(100 * s.dropout_share, 2) + ' %'] };
        }));
    }
  }

  // ------------------------------------------------------------------ runs
  const runsSection = document.getElementById('runs');
  if (data.runs.length) {
    runsSection.appendChild(el('h2', '', data.comparisons.length
      ? `Runs of the first seed (${data.runs.map((r) => r.label).join(', ')})`
      : (data.runs.length > 1 ? `Runs (${data.runs.map((r) => r.label).join(', ')})` : 'Run')));
    const grid = el('div', 'grid');
    runsSection.appendChild(grid);

    // Map: estimate vs truth vs raw GNSS, outages and jumps marked.
    const mapSets = [];
    const seenData = new Set();
    for (const run of data.runs) {
      if (seenData.has(run.dataset)) continue;
      seenData.add(run.dataset);
      if (run.gnss) {
        const jumps = run.events.filter((e) => e.type === 'jump');
        const inJump = (t) => jumps.some((e) => t >= e.t0 && t < e.t1);
        const normal = [], jumped = [];
        run.gnss.t.forEach((t, i) => (inJump(t) ? jumped : normal).push({ x: run.gnss.e[i], y: run.gnss.n[i] }));
        mapSets.push({ label: 'raw GNSS fixes', data: normal, pointRadius: 1.6, backgroundColor: 'rgba(95,107,122,0.45)', order: 5 });
        if (jumped.length) mapSets.push({ label: 'GNSS fixes during a jump', data: jumped, pointRadius: 2.6, backgroundColor: 'rgba(224,120,20,0.95)', order: 4 });
      }
      if (run.truth) {
        mapSets.push({ label: 'ground truth', data: xy(run.truth.e, run.truth.n), showLine: true, borderColor: '#1d2733', borderWidth: 1.2, order: 3 });
        const outages = run.events.filter((e) => e.type === 'outage');
        if (outages.length) {
          const seg = [];
          run.truth.t.forEach((t, i) => {
            if (outages.some((e) => t >= e.t0 && t < e.t1)) seg.push({ x: run.truth.e[i], y: run.truth.n[i] });
            else if (seg.length && seg[seg.length - 1].x !== null) seg.push({ x: null, y: null });
          });
          mapSets.push({ label: 'track during a GNSS outage', data: seg, showLine: true, borderColor: 'rgba(192,57,43,0.55)', borderWidth: 7, spanGaps: false, order: 6 });
        }
      }
    }
    for (const run of data.runs) {
      mapSets.push({ label: `${run.label} estimate`, data: xy(run.estimate.e, run.estimate.n), showLine: true, borderColor: color(run.label), borderWidth: 1.6, order: 1 });
    }
    const mapChart = chart(panel(grid, 'Trajectory (local ENU)', 'Equal scales in east and north. Grey band: the true track while GNSS is out; orange dots: fixes during a jump.', 'map'), {
      type: 'scatter', data: { datasets: mapSets },
      options: { scales: { x: { ticks: { includeBounds: false }, title: { display: true, text: 'east (m)' } }, y: { ticks: { includeBounds: false }, title: { display: true, text: 'north (m)' } } } }
    });
    // Equal axis scales: fit the data's extent to the plot area's aspect ratio.
    (function equalAxes(c) {
      let minX = Infinity, maxX = -Infinity, minY = Infinity, maxY = -Infinity;
      for (const ds of c.data.datasets) for (const p of ds.data) {
        if (p.x === null || p.y === null) continue;
        minX = Math.min(minX, p.x); maxX = Math.max(maxX, p.x); minY = Math.min(minY, p.y); maxY = Math.max(maxY, p.y);
      }
      if (!isFinite(minX)) return;
      const a = c.chartArea, aspect = (a.right - a.left) / Math.max(1, a.bottom - a.top);
      let w = (maxX - minX) * 1.06 + 1, h = (maxY - minY) * 1.06 + 1;
      if (w / h > aspect) h = w / aspect; else w = h * aspect;
      const cx = (minX + maxX) / 2, cy = (minY + maxY) / 2;
      c.options.scales.x.min = cx - w / 2; c.options.scales.x.max = cx + w / 2;
      c.options.scales.y.min = cy - h / 2; c.options.scales.y.max = cy + h / 2;
      c.update('none');
    })(mapChart);

    const withErrors = data.runs.filter((r) => r.errors);
    const spans = withErrors.length ? spansOf(withErrors[0]) : [];
    if (withErrors.length) {
      const errSets = [];
      for (const run of withErrors) {
        errSets.push({ label: `${run.label} error`, data: xy(run.errors.t, run.errors.h, 1e-3), borderColor: color(run.label) });
        errSets.push({ label: `${run.label} 3σ`, data: xy(run.errors.t, run.errors.h3s, 1e-3), borderColor: rgba(color(run.label), 0.6), borderDash: [6, 4], borderWidth: 1 });
      }
      chart(panel(grid, 'Horizontal position error and 3σ bound', 'Solid: |error| against ground truth; dashed: 3 × the estimator\'s own horizontal σ. Log scale.'), {
        type: 'line', data: { datasets: errSets },
        options: { plugins: { spans: { spans } }, scales: { x: timeAxis, y: { type: 'logarithmic', title: { display: true, text: 'm' } } } }
      });

      const [b0, b1] = data.nees_bounds_95;
      const t0 = Math.min(...withErrors.map((r) => r.errors.t[0]));
      const t1 = Math.max(...withErrors.map((r) => r.errors.t[r.errors.t.length - 1]));
      const neesSets = withErrors.map((run) => ({ label: run.label, data: xy(run.errors.t, run.errors.nees, 1e-3), borderColor: color(run.label), borderWidth: 1 }));
      neesSets.push({ label: `95% bounds of one epoch (χ², 3 dof): ${b0.toFixed(2)}, ${b1.toFixed(2)}`, data: [{ x: t0, y: b1 }, { x: t1, y: b1 }], borderColor: '#1d2733', borderDash: [5, 4], borderWidth: 1.2 });
      neesSets.push({ label: '', data: [{ x: t0, y: b0 }, { x: t1, y: b0 }], borderColor: '#1d2733', borderDash: [5, 4], borderWidth: 1.2 });
      chart(panel(grid, 'Position NEES', 'Normalised estimation error squared of the newest state; a consistent estimator stays between the bounds 95% of the time. Log scale.'), {
        type: 'line', data: { datasets: neesSets },
        options: { plugins: { spans: { spans }, legend: { labels: { filter: (i) => i.text !== '' } } }, scales: { x: timeAxis, y: { type: 'logarithmic', title: { display: true, text: 'NEES' } } } }
      });

      const hdgSets = [];
      for (const run of withErrors) {
        hdgSets.push({ label: `${run.label} error`, data: xy(run.errors.t, run.errors.hdg), borderColor: color(run.label) });
        hdgSets.push({ label: `${run.label} ±3σ`, data: xy(run.errors.t, run.errors.hdg3s), borderColor: rgba(color(run.label), 0.6), borderDash: [6, 4], borderWidth: 1 });
        hdgSets.push({ label: '', data: xy(run.errors.t, run.errors.hdg3s.map((v) => (v === null ? null : -v))), borderColor: rgba(color(run.label), 0.6), borderDash: [6, 4], borderWidth: 1 });
      }
      chart(panel(grid, 'Heading error and ±3σ', 'Estimate − truth, degrees (heading clockwise from north).'), {
        type: 'line', data: { datasets: hdgSets },
        options: { plugins: { spans: { spans }, legend: { labels: { filter: (i) => i.text !== '' } } }, scales: { x: timeAxis, y: { title: { display: true, text: 'deg' } } } }
      });
    }

    const withUpdates = data.runs.filter((r) => r.updates);
    if (withUpdates.length) {
      chart(panel(grid, 'Solver time per update', 'Wall time of each window update (the maximum of each plotted bucket). Log scale.'), {
        type: 'line',
        data: { datasets: withUpdates.map((run) => ({ label: run.label, data: xy(run.updates.t, run.updates.ms, 1e-3), borderColor: color(run.label), borderWidth: 1 })) },
        options: { plugins: { spans: { spans } }, scales: { x: timeAxis, y: { type: 'logarithmic', title: { display: true, text: 'ms' } } } }
      });
    }
  }

  // ------------------------------------------------------------------ self-check
  function painted(c) {
    const a = c.chartArea, r = c.currentDevicePixelRatio || 1;
    const w = Math.floor((a.right - a.left) * r), h = Math.floor((a.bottom - a.top) * r);
    if (w <= 0 || h <= 0) return 0;
    const px = c.ctx.getImageData(Math.floor(a.left * r), Math.floor(a.top * r), w, h).data;
    let n = 0;
    for (let i = 0; i < px.length; i += 4) {
      const mx = Math.max(px[i], px[i + 1], px[i + 2]), mn = Math.min(px[i], px[i + 1], px[i + 2]);
      if (px[i + 3] > 100 && mx - mn > 40) n++;
    }
    return n;
  }
  // Layout can lag the first frame on a loaded machine (a chart area still 0 x 0): look again a
  // few times before reporting what is painted.
  function selfCheck(tries) {
    let ok = 0;
    for (const c of charts) {
      c.draw();
      const n = painted(c);
      c.canvas.setAttribute('data-painted', String(n));
      if (n > 200) ok++;
    }
    document.body.setAttribute('data-charts-drawn', String(charts.length));
    document.body.setAttribute('data-charts-painted', String(ok));
    if (ok < charts.length && tries > 0) setTimeout(() => selfCheck(tries - 1), 250);
  }
  window.requestAnimationFrame(() => setTimeout(() => selfCheck(20), 0));
})();
