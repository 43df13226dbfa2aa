// explorer.html's own script (experiments.render.explorer): reads the embedded JSON, draws with Plotly,
// wires check boxes, clicks, sorting and filters
(function () {
  var DATA = JSON.parse(document.getElementById('explorer-data').textContent);
  var cfg = {displaylogo: false, responsive: true};
  // Plotly reads a few HTML tags in its text (legends, titles, ticks): user text goes in with <, >, & escaped
  function esc(s) { return String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;'); }
  window.explorer = {data: DATA, figures: []};
  // Plotly's default colours, so that a method has one colour in every plot of its ranking
  var COLOURS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22',
                 '#17becf'];
  // a title left-aligned just above the plot area, below the mode bar (which sits at the top right of the figure)
  function titled(text) {
    return {text: text, x: 0, xref: 'paper', xanchor: 'left', y: 1, yref: 'paper', yanchor: 'bottom', pad: {b: 6}};
  }
  var TOP = 64;
  DATA.forEach(function (r, k) {
    var n = k + 1, label = esc(r.label || r.metric);
    var prof = r.methods.map(function (m, j) {
      return {x: r.profile.tau, y: r.profile.rho[m], name: esc(m), mode: 'lines', line: {shape: 'hv',
              color: COLOURS[j % COLOURS.length]}, meta: j};
    });
    Plotly.newPlot('profile-' + n, prof, {title: titled('Performance profile: ' + label),
      xaxis: {title: {text: 'τ (cost / best cost)'}, type: 'log'}, yaxis: {title: {text: 'ρ(τ): share of problems'},
      range: [0, 1.02]}, legend: {font: {size: 9}}, margin: {t: TOP}}, cfg);
    var figs = ['profile-' + n];
    if (r.time) {
      // one panel per unit (r.panels): costs of different units (mm, R) never share an axis
      var untimed = r.untimed.length ? ' (not timed: ' + r.untimed.map(esc).join(', ') + ')' : '';
      var rt = [], units = r.panels.map(function (p) { return p.unit; });
      var layout = {title: titled(label + ' against runtime' + untimed), showlegend: false, margin: {t: TOP},
                    grid: {rows: units.length, columns: 1, pattern: 'independent', roworder: 'top to bottom'}};
      r.panels.forEach(function (panel, g) {
        var rows = panel.problems, u = panel.unit, ax = g ? String(g + 1) : '';
        r.methods.forEach(function (m, j) {
          rt.push({x: rows.map(function (i) { return r.time[i][j]; }), y: rows.map(function (i) { return r.cost[i][j]; }),
                   text: rows.map(function (i) { return esc(r.problems[i]); }), name: esc(m), mode: 'markers',
                   type: 'scatter', marker: {size: 5, color: COLOURS[j % COLOURS.length]}, meta: j,
                   xaxis: 'x' + ax, yaxis: 'y' + ax,
                   hovertemplate: '%{text}<br>' + esc(m) + '<br>%{x} s, ' + label + ' %{y}' + (u ? ' ' + esc(u) : '') +
                                  '<extra></extra>'});
        });
        layout['xaxis' + ax] = {title: {text: 'median runtime [s]'}, type: 'log'};
        layout['yaxis' + ax] = {title: {text: label + (u ? ' [' + esc(u) + ']' : '')}, type: 'log'};
      });
      var el = document.getElementById('runtime-' + n);
      if (units.length > 1) { el.style.height = (420 + 240 * (units.length - 1)) + 'px'; }
      Plotly.newPlot(el, rt, layout, cfg);
      figs.push('runtime-' + n);
    } else {
      document.getElementById('runtime-' + n).textContent = r.no_time ||
        'The studies of this ranking did not time their fits.';
    }
    var z = r.ratio.map(function (row) { return row.map(function (v) { return v === null ? null : Math.log10(v); }); });
    Plotly.newPlot('map-' + n, [{type: 'heatmap', z: z, x: r.methods.map(esc), y: r.problems.map(esc), colorscale: [[0, '#1a9850'], [0.25, '#d9ef8b'], [0.5, '#fee08b'], [1, '#d73027']],
      zmin: 0, zmax: 1, colorbar: {title: {text: 'log₁₀ ratio<br>(blank: failed)'}},
      text: r.cost.map(function (row, i) { return row.map(function (v) {   // each problem's cost in its study's unit
        return v === null ? 'failed or not run' : v + ' ' + esc(r.units[i]); }); }),
      hovertemplate: '%{y}<br>%{x}<br>' + label + ' %{text}<extra></extra>'}],
      {title: titled('Ratio to the best method per problem'), xaxis: {tickangle: 45, tickfont: {size: 8}},
       yaxis: {showticklabels: false, title: {text: 'problems'}}, margin: {t: TOP, b: 110}}, cfg);
    document.getElementById('map-' + n).on('plotly_click', function (ev) {
      var ij = ev.points[0].pointNumber;          // [problem row, method column]
      explorer.showFit(k, r.problems[ij[0]], r.methods[ij[1]]);
    });
    explorer.figures.push(figs);
    document.querySelectorAll('#ranking-' + n + ' input[data-method]').forEach(function (box) {
      box.addEventListener('change', function () {
        var j = +box.getAttribute('data-method');
        figs.forEach(function (id) {       // every trace of method j (meta: its index), in every panel
          var traces = [];
          document.getElementById(id).data.forEach(function (t, i) { if (t.meta === j) { traces.push(i); } });
          Plotly.restyle(id, {visible: box.checked ? true : 'legendonly'}, traces);
        });
      });
    });
  });
  explorer.showFit = function (k, problem, method) {
    var r = DATA[k], n = k + 1, f = r.fits[problem], el = document.getElementById('fit-' + n);
    if (!f || !f.methods[method]) {
      Plotly.purge(el);
      el.textContent = 'No drawing for ' + problem + ' / ' + method + ': its points or fit are not embedded ' +
        '(only the first problems of a ranking are, and only where the data source is available here).';
      return false;
    }
    var m = f.methods[method];
    Plotly.newPlot(el, [
      {x: f.x, y: f.y, mode: 'markers', name: 'points', marker: {size: 4, color: '#444'}, xaxis: 'x', yaxis: 'y'},
      {x: m.x, y: m.y, mode: 'lines', name: esc(method + ' (' + m.status + ')'), xaxis: 'x', yaxis: 'y'},
      {x: f.angle, y: m.residual, mode: 'markers', name: 'residual', marker: {size: 4}, xaxis: 'x2', yaxis: 'y2'}],
      {title: Object.assign(titled(esc(problem) + '<br>' + esc(method)), {font: {size: 11}}), showlegend: false,
       grid: {rows: 2, columns: 1, pattern: 'independent'},
       xaxis: {title: {text: 'x (units of the data)'}, scaleanchor: 'y'}, yaxis: {title: {text: 'y'}},
       xaxis2: {title: {text: 'angle about the centroid [°]'}},
       yaxis2: {title: {text: 'residual (units of the data)'}}, margin: {t: TOP + 16}}, cfg);
    el.setAttribute('data-problem', problem);
    el.setAttribute('data-method', method);
    return true;
  };
  function cellValue(td) {         // the number as shown (4.07×10⁻⁵), without a coloured cell's ratio line
    var t = (td.firstChild ? td.firstChild.textContent : '').trim().replace('×10', 'e').replace(/[⁻⁰¹²³⁴⁵⁶⁷⁸⁹]/g, function (c) {
      return '-0123456789'['⁻⁰¹²³⁴⁵⁶⁷⁸⁹'.indexOf(c)];
    });
    var v = parseFloat(t);
    return isNaN(v) ? t.toLowerCase() : v;
  }
  document.querySelectorAll('.explorer-table table').forEach(function (table) {
    table.querySelectorAll('thead th').forEach(function (th, col) {
      th.addEventListener('click', function () {
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var asc = !th.classList.contains('sorted-asc');
        table.querySelectorAll('thead th').forEach(function (h) { h.classList.remove('sorted-asc', 'sorted-desc'); });
        th.classList.add(asc ? 'sorted-asc' : 'sorted-desc');
        rows.sort(function (a, b) {
          var x = cellValue(a.cells[col]), y = cellValue(b.cells[col]);
          if (typeof x !== typeof y) { return (typeof x === 'number' ? -1 : 1); }
          return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1);
        });
        rows.forEach(function (row) { body.appendChild(row); });
      });
    });
  });
  document.querySelectorAll('input.filter').forEach(function (box) {
    box.addEventListener('input', function () {
      var q = box.value.toLowerCase(), table = document.getElementById(box.getAttribute('data-table'));
      Array.prototype.forEach.call(table.tBodies[0].rows, function (row) {
        row.style.display = row.textContent.toLowerCase().indexOf(q) >= 0 ? '' : 'none';
      });
    });
  });
  document.body.setAttribute('data-explorer', 'ready');
})();
