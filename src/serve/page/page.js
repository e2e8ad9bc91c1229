'use strict';
// The planner page: the scene as edited (the server's SceneEdit JSON), drawn to scale with handles; each
// edit is sent to /api/solve, the answer drawn (paths coloured by speed, hulls, the table) or its error
// shown where the edit was made. Everything here comes from this server; nothing is fetched elsewhere.
(function () {
  var SVG_NS = 'http://www.w3.org/2000/svg';
  var W = 960, H = 720, PAD = 48;
  var HULL_HALF = 16;          // units: the 32 x 32 player hull
  var ARROW_S = 0.5;           // the velocity arrow is the distance covered in this many seconds
  var HULLS_PER_RUN = 5;
  var SPEED_STOPS = ['#313695', '#4575b4', '#74add1', '#abd9e9', '#fdae61', '#f46d43', '#d73027', '#a50026'];
  var SPEED_BINS = 32;

  function $(id) { return document.getElementById(id); }
  var svg = $('plot');
  var layers = {};
  ['grid', 'paths', 'hulls', 'walls', 'finish', 'start', 'handles', 'cursor'].forEach(function (n) { layers[n] = $(n); });

  var model = null;            // the scene as edited
  var solvedModel = null;      // the scene of the result drawn
  var result = null;           // the answer drawn
  var quality = 'fast';
  var timeLimit = 20;
  var view = { cx: 0, cy: 0, k: 1 };  // screen = (W/2 + (x - cx) k, H/2 - (y - cy) k)
  var selected = null;         // { wall, point }
  var drag = null, pan = null;
  var sent = 0;                // edits sent
  var waiting = 0;             // answers not yet come
  var progressTimer = null;
  var bad = null;              // { wall, point } or a field id, marked in red

  function clone(v) { return JSON.parse(JSON.stringify(v)); }
  function toScreen(p) { return [W / 2 + (p[0] - view.cx) * view.k, H / 2 - (p[1] - view.cy) * view.k]; }
  function toWorld(s) { return [view.cx + (s[0] - W / 2) / view.k, view.cy - (s[1] - H / 2) / view.k]; }
  function svgPoint(evt) {
    var pt = svg.createSVGPoint();
    pt.x = evt.clientX; pt.y = evt.clientY;
    var q = pt.matrixTransform(svg.getScreenCTM().inverse());
    return [q.x, q.y];
  }
  // Where an SVG point is inside #view, in CSS pixels.
  function inView(s) {
    var pt = svg.createSVGPoint();
    pt.x = s[0]; pt.y = s[1];
    var c = pt.matrixTransform(svg.getScreenCTM());
    var r = $('view').getBoundingClientRect();
    return [c.x - r.left, c.y - r.top];
  }
  function el(tag, attrs, parent) {
    var e = document.createElementNS(SVG_NS, tag);
    Object.keys(attrs).forEach(function (k) { e.setAttribute(k, attrs[k]); });
    if (parent) { parent.appendChild(e); }
    return e;
  }
  function clear(g) { while (g.firstChild) { g.removeChild(g.firstChild); } }
  function pts(list) { return list.map(function (p) { var s = toScreen(p); return s[0].toFixed(2) + ',' + s[1].toFixed(2); }).join(' '); }
  function round1(v) { return Math.round(v); }

  // ---- view ----
  function fit() {
    var xs = [], ys = [];
    function add(p) { xs.push(p[0]); ys.push(p[1]); }
    model.walls.forEach(function (w) { w.points.forEach(add); });
    add(model.start.position); add(model.finish.a); add(model.finish.b);
    var fin = function (v) { return isFinite(v); };
    xs = xs.filter(fin); ys = ys.filter(fin);
    if (!xs.length) { view = { cx: 0, cy: 0, k: 1 }; return; }
    var x0 = Math.min.apply(null, xs), x1 = Math.max.apply(null, xs);
    var y0 = Math.min.apply(null, ys), y1 = Math.max.apply(null, ys);
    var k = Math.min((W - 2 * PAD) / Math.max(x1 - x0, 1), (H - 2 * PAD) / Math.max(y1 - y0, 1));
    view = { cx: (x0 + x1) / 2, cy: (y0 + y1) / 2, k: k };
  }

  function niceStep(raw) {
    var p = Math.pow(10, Math.floor(Math.log10(raw)));
    var m = raw / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  }

  function drawGrid() {
    var g = layers.grid; clear(g);
    var step = niceStep(100 / view.k);
    var a = toWorld([0, H]), b = toWorld([W, 0]);
    for (var x = Math.ceil(a[0] / step) * step; x <= b[0]; x += step) {
      var sx = toScreen([x, 0])[0];
      el('line', { x1: sx, y1: 0, x2: sx, y2: H, class: 'grid-line' }, g);
      el('text', { x: sx + 3, y: H - 4, class: 'grid-label' }, g).textContent = String(Math.round(x));
    }
    for (var y = Math.ceil(a[1] / step) * step; y <= b[1]; y += step) {
      var sy = toScreen([0, y])[1];
      el('line', { x1: 0, y1: sy, x2: W, y2: sy, class: 'grid-line' }, g);
      el('text', { x: 3, y: sy - 3, class: 'grid-label' }, g).textContent = String(Math.round(y));
    }
  }

  // ---- the scene ----
  function isBad(wall, point) {
    return bad && typeof bad === 'object' && bad.wall === wall && (point === undefined || bad.point === undefined || bad.point === point);
  }

  function drawScene() {
    clear(layers.walls); clear(layers.handles); clear(layers.start); clear(layers.finish);
    model.walls.forEach(function (w, i) {
      var tag = w.closed ? 'polygon' : 'polyline';
      el(tag, { points: pts(w.points), class: 'wall ' + w.kind + (isBad(i) ? ' bad' : '') }, layers.walls);
      el(tag, { points: pts(w.points), class: 'wall-hit', 'data-hit-wall': i }, layers.walls);
      w.points.forEach(function (p, j) {
        var s = toScreen(p);
        var sel = selected && selected.wall === i && selected.point === j;
        el('circle', {
          cx: s[0], cy: s[1], r: 6, 'data-kind': 'wall', 'data-wall': i, 'data-point': j,
          class: 'handle' + (sel ? ' selected' : '') + (isBad(i, j) ? ' bad' : '')
        }, layers.handles).appendChild(document.createElementNS(SVG_NS, 'title')).textContent =
          'walls[' + i + '].points[' + j + '] (' + p[0] + ', ' + p[1] + ')';
      });
    });
    var f = model.finish, fa = toScreen(f.a), fb = toScreen(f.b);
    el('line', { x1: fa[0], y1: fa[1], x2: fb[0], y2: fb[1], class: 'finish-line' }, layers.finish);
    el('circle', { cx: fa[0], cy: fa[1], r: 6, 'data-kind': 'finish-a', class: 'handle finish' + (bad === 'finish' ? ' bad' : '') }, layers.handles);
    el('circle', { cx: fb[0], cy: fb[1], r: 6, 'data-kind': 'finish-b', class: 'handle finish' + (bad === 'finish' ? ' bad' : '') }, layers.handles);
    var st = model.start, c = toScreen(st.position), h = HULL_HALF * view.k;
    var tip = toScreen([st.position[0] + st.velocity[0] * ARROW_S, st.position[1] + st.velocity[1] * ARROW_S]);
    el('line', { x1: c[0], y1: c[1], x2: tip[0], y2: tip[1], class: 'velocity' }, layers.start);
    el('rect', {
      x: c[0] - Math.max(h, 5), y: c[1] - Math.max(h, 5), width: 2 * Math.max(h, 5), height: 2 * Math.max(h, 5),
      'data-kind': 'start-position', class: 'start-hull' + (bad === 'start' ? ' bad' : '')
    }, layers.handles);
    el('circle', { cx: tip[0], cy: tip[1], r: 6, 'data-kind': 'start-velocity', class: 'handle start' + (bad === 'start' ? ' bad' : '') }, layers.handles);
    $('scene-name').textContent = model.name;
    $('fps').value = model.engine.vars.fps === null || model.engine.vars.fps === undefined ? '' : model.engine.vars.fps;
    var aa = model.engine.vars.airaccelerate;
    $('airaccelerate').value = aa === null || aa === undefined ? '' : aa;
    $('airaccelerate').placeholder = 'preset (' + model.engine.preset + ')';
    $('quality').value = quality;
    drawPointEditor();
  }

  function drawPointEditor() {
    var fs = $('point-editor');
    if (!selected || !model.walls[selected.wall] || !model.walls[selected.wall].points[selected.point]) {
      selected = null; fs.disabled = true; $('point-name').textContent = 'click a wall point to select it';
      $('point-x').value = ''; $('point-y').value = '';
      return;
    }
    var p = model.walls[selected.wall].points[selected.point];
    fs.disabled = false;
    if (document.activeElement !== $('point-x')) { $('point-x').value = p[0]; }
    if (document.activeElement !== $('point-y')) { $('point-y').value = p[1]; }
    $('point-name').textContent = 'walls[' + selected.wall + '].points[' + selected.point + ']';
  }

  // ---- the result ----
  function speedColour(t) {
    t = Math.min(1, Math.max(0, t));
    var x = t * (SPEED_STOPS.length - 1), i = Math.min(Math.floor(x), SPEED_STOPS.length - 2), f = x - i;
    function rgb(h) { return [1, 3, 5].map(function (k) { return parseInt(h.substr(k, 2), 16); }); }
    var a = rgb(SPEED_STOPS[i]), b = rgb(SPEED_STOPS[i + 1]);
    return 'rgb(' + a.map(function (v, k) { return Math.round(v + (b[k] - v) * f); }).join(',') + ')';
  }

  function speedRange() {
    var lo = Infinity, hi = -Infinity;
    result.runs.forEach(function (r) { r.speed.forEach(function (s) { if (s < lo) { lo = s; } if (s > hi) { hi = s; } }); });
    if (!(hi > lo)) { hi = lo + 1; }
    return [lo, hi];
  }

  function drawRun(run, range) {
    var g = el('g', { class: 'run', 'data-run': run.label }, layers.paths);
    var n = run.x.length, bin = -1, line = [];
    function at(i) { var s = toScreen([run.x[i], run.y[i]]); return s[0].toFixed(2) + ',' + s[1].toFixed(2); }
    function flush() {
      if (line.length > 1) {
        el('polyline', { points: line.join(' '), class: 'path ' + run.label, stroke: speedColour((bin + 0.5) / SPEED_BINS) }, g);
      }
    }
    // One polyline per run of frames in the same speed bin (a segment takes its mean speed).
    for (var i = 1; i < n; i++) {
      var sp = (run.speed[i - 1] + run.speed[i]) / 2;
      var b = Math.min(SPEED_BINS - 1, Math.max(0, Math.floor((sp - range[0]) / (range[1] - range[0]) * SPEED_BINS)));
      if (b !== bin) { flush(); line = [at(i - 1)]; bin = b; }
      line.push(at(i));
    }
    flush();
    var h = HULL_HALF * view.k;
    for (var k = 1; k <= HULLS_PER_RUN; k++) {
      var f = Math.round((n - 1) * k / HULLS_PER_RUN);
      var c = toScreen([run.x[f], run.y[f]]);
      el('rect', { x: c[0] - h, y: c[1] - h, width: 2 * h, height: 2 * h, class: 'hull ' + run.label, 'data-frame': f }, layers.hulls)
        .appendChild(document.createElementNS(SVG_NS, 'title')).textContent = run.label + ', frame ' + f;
    }
  }

  function drawResult() {
    clear(layers.paths); clear(layers.hulls); clear(layers.cursor);
    if (!result) { return; }
    var range = speedRange();
    // Greedy under the plan.
    drawRun(result.runs[0], range);
    drawRun(result.runs[1], range);
    layers.paths.setAttribute('data-result-id', result.id);
    $('speed-min').textContent = range[0].toFixed(0);
    $('speed-max').textContent = range[1].toFixed(0);
    $('speed-scale').style.background = 'linear-gradient(to right, ' + SPEED_STOPS.join(', ') + ')';
  }

  function fmtTime(t) { return t === null || t === undefined ? 'not reached' : t.toFixed(6); }
  function setRow(id, frames, time, valid) {
    var row = $(id);
    row.querySelector('.frames').textContent = frames === null || frames === undefined ? '-' : frames;
    row.querySelector('.time').textContent = fmtTime(time);
    row.querySelector('.valid').textContent = valid === null ? '' : valid ? 'yes' : 'no';
  }
  function statusText(s) {
    if (!s) { return ''; }
    switch (s.status) {
      case 'converged': return 'converged';
      case 'time-limit': return 'stopped by the time limit (best valid plan so far)';
      case 'greedy-optimal': return 'greedy is optimal: ' + s.reason;
      case 'no-improvement': return 'greedy plan: ' + s.reason;
      default: return s.status + (s.reason ? ': ' + s.reason : '');
    }
  }

  function drawTable() {
    if (!result) { return; }
    var s = result.summary;
    setRow('row-optimised', s.frames, s.time, s.feasible);
    setRow('row-engine-exact', s.engine_exact.frames, s.engine_exact.time, s.engine_exact.feasible);
    setRow('row-greedy', s.greedy.frames, s.greedy.time, s.greedy.feasible);
    setRow('row-bound', s.lower_bound.frames, s.lower_bound.time, null);
    $('gap').textContent = s.gap_to_lower_bound === null ? '-' : (100 * s.gap_to_lower_bound).toFixed(3) + ' %';
    $('gain').textContent = s.greedy.feasible && s.time !== null && s.greedy.time !== null
      ? (s.greedy.time - s.time).toFixed(6) + ' s (' + (s.greedy.frames - s.frames) + ' frames)' : '-';
    $('status').textContent = statusText(s.status) + ' (' + s.source + ', ' + s.quality + ')';
    $('solve-time').textContent = s.solve_seconds.toFixed(2) + ' s, ' + s.stats.iterations + ' iterations';
    ['dl-toml', 'dl-hltas', 'dl-csv', 'dl-report'].forEach(function (id) { $(id).classList.remove('disabled'); });
  }

  // ---- pointer: hover, drag, pan, zoom ----
  function hover(s) {
    clear(layers.cursor);
    var tip = $('tooltip');
    if (!result) { tip.hidden = true; return; }
    var best = null, bestD = 18 * 18;
    result.runs.forEach(function (run) {
      for (var i = 0; i < run.x.length; i++) {
        var p = toScreen([run.x[i], run.y[i]]);
        var d = (p[0] - s[0]) * (p[0] - s[0]) + (p[1] - s[1]) * (p[1] - s[1]);
        if (d < bestD) { bestD = d; best = { run: run, i: i, p: p }; }
      }
    });
    if (!best) { tip.hidden = true; return; }
    el('circle', { cx: best.p[0], cy: best.p[1], r: 7, class: 'cursor-dot' }, layers.cursor);
    var r = best.run;
    tip.textContent = r.label + ': frame ' + best.i + ', ' + (best.i * result.frame_time_s).toFixed(3) + ' s, ' +
      r.speed[best.i].toFixed(1) + ' ups';
    var at = inView(best.p);
    tip.style.left = (at[0] + 12) + 'px';
    tip.style.top = (at[1] - 28) + 'px';
    tip.hidden = false;
  }

  svg.addEventListener('pointerdown', function (e) {
    if (e.button !== 0) { return; }
    var t = e.target, kind = t.getAttribute('data-kind');
    if (kind) {
      drag = { kind: kind, wall: +t.getAttribute('data-wall'), point: +t.getAttribute('data-point'), moved: false };
      if (kind === 'wall') { selected = { wall: drag.wall, point: drag.point }; drawPointEditor(); }
      svg.setPointerCapture(e.pointerId);
      e.preventDefault();
    } else if (!t.hasAttribute('data-hit-wall')) {
      pan = { from: svgPoint(e), view: clone(view) };
      svg.setPointerCapture(e.pointerId);
    }
  });

  svg.addEventListener('pointermove', function (e) {
    var s = svgPoint(e);
    if (drag) {
      var w = toWorld(s), p = [round1(w[0]), round1(w[1])];
      if (drag.kind === 'wall') { model.walls[drag.wall].points[drag.point] = p; }
      else if (drag.kind === 'finish-a') { model.finish.a = p; }
      else if (drag.kind === 'finish-b') { model.finish.b = p; }
      else if (drag.kind === 'start-position') { model.start.position = p; }
      else if (drag.kind === 'start-velocity') {
        var o = model.start.position;
        model.start.velocity = [round1((w[0] - o[0]) / ARROW_S), round1((w[1] - o[1]) / ARROW_S)];
      }
      drag.moved = true;
      drawScene();
      return;
    }
    if (pan) {
      view.cx = pan.view.cx - (s[0] - pan.from[0]) / view.k;
      view.cy = pan.view.cy + (s[1] - pan.from[1]) / view.k;
      drawAll();
      return;
    }
    hover(s);
  });

  function endPointer() {
    if (drag && drag.moved) {
      var where = drag.kind === 'wall' ? { wall: drag.wall, point: drag.point }
        : drag.kind.indexOf('finish') === 0 ? 'finish' : 'start';
      drag = null;
      edit(where);
    }
    drag = null; pan = null;
  }
  svg.addEventListener('pointerup', endPointer);
  svg.addEventListener('pointercancel', endPointer);
  svg.addEventListener('pointerleave', function () { if (!drag) { clear(layers.cursor); $('tooltip').hidden = true; } });

  svg.addEventListener('wheel', function (e) {
    e.preventDefault();
    var s = svgPoint(e), w = toWorld(s);
    view.k *= Math.exp(-e.deltaY * 0.0015);
    view.cx = w[0] - (s[0] - W / 2) / view.k;
    view.cy = w[1] + (s[1] - H / 2) / view.k;
    drawAll();
  }, { passive: false });

  svg.addEventListener('dblclick', function (e) {
    var t = e.target, s = svgPoint(e);
    if (t.getAttribute('data-kind') === 'wall') {
      var wall = model.walls[+t.getAttribute('data-wall')];
      if (wall.points.length <= 2) { showError({ wall: +t.getAttribute('data-wall') }, 'a wall keeps at least two points'); return; }
      wall.points.splice(+t.getAttribute('data-point'), 1);
      selected = null;
      edit({ wall: +t.getAttribute('data-wall') });
    } else if (t.hasAttribute('data-hit-wall')) {
      var i = +t.getAttribute('data-hit-wall'), w = model.walls[i], q = toWorld(s);
      var best = 0, bestD = Infinity, bestP = null, n = w.points.length, segs = w.closed ? n : n - 1;
      for (var j = 0; j < segs; j++) {
        var a = w.points[j], b = w.points[(j + 1) % n];
        var dx = b[0] - a[0], dy = b[1] - a[1], L = dx * dx + dy * dy;
        var u = L > 0 ? Math.max(0, Math.min(1, ((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / L)) : 0;
        var px = a[0] + u * dx, py = a[1] + u * dy, d = (q[0] - px) * (q[0] - px) + (q[1] - py) * (q[1] - py);
        if (d < bestD) { bestD = d; best = j; bestP = [round1(px), round1(py)]; }
      }
      w.points.splice(best + 1, 0, bestP);
      selected = { wall: i, point: best + 1 };
      edit({ wall: i, point: best + 1 });
    }
  });

  document.addEventListener('keydown', function (e) {
    if ((e.key === 'Delete' || e.key === 'Backspace') && selected && document.activeElement.tagName !== 'INPUT') {
      $('point-remove').click();
    }
  });

  // ---- controls ----
  function numberOrNull(v) { return v === '' ? null : Number(v); }
  $('fps').addEventListener('change', function () { model.engine.vars.fps = numberOrNull(this.value); edit('fps'); });
  $('airaccelerate').addEventListener('change', function () { model.engine.vars.airaccelerate = numberOrNull(this.value); edit('airaccelerate'); });
  $('quality').addEventListener('change', function () { quality = this.value; edit('quality'); });
  function pointInput(axis) {
    return function () {
      if (!selected) { return; }
      var v = Number(this.value), where = { wall: selected.wall, point: selected.point };
      if (this.value === '' || !isFinite(v)) {
        showError(where, 'walls[' + where.wall + '].points[' + where.point + ']: ' + (axis ? 'y' : 'x') + ' must be a number');
        return;
      }
      model.walls[where.wall].points[where.point][axis] = v;
      edit(where);
    };
  }
  $('point-x').addEventListener('change', pointInput(0));
  $('point-y').addEventListener('change', pointInput(1));
  $('point-remove').addEventListener('click', function () {
    if (!selected) { return; }
    var w = model.walls[selected.wall], where = { wall: selected.wall };
    if (w.points.length <= 2) { showError(where, 'a wall keeps at least two points'); return; }
    w.points.splice(selected.point, 1);
    selected = null;
    edit(where);
  });
  $('revert').addEventListener('click', function () {
    if (!solvedModel) { return; }
    model = clone(solvedModel);
    bad = null; hideError(); selected = null;
    $('revert').disabled = true;
    $('result-note').textContent = '';
    $('results').classList.remove('stale');
    drawScene();
  });
  $('fit').addEventListener('click', function () { fit(); drawAll(); });

  // ---- errors ----
  function hideError() {
    $('edit-error').hidden = true; $('settings-error').hidden = true;
    ['fps', 'airaccelerate', 'quality'].forEach(function (id) { $(id).classList.remove('bad'); });
  }

  // Shows `message` where the edit `where` was made: beside the point, the start or the finish in the
  // drawing, or under the setting.
  function showError(where, message) {
    hideError();
    bad = where;
    if (typeof where === 'string' && $(where) && $(where).tagName !== 'svg') {
      $(where).classList.add('bad');
      $('settings-error').textContent = message;
      $('settings-error').hidden = false;
      drawScene();
      return;
    }
    drawScene();
    var anchor = null;
    if (where && typeof where === 'object') {
      var w = model.walls[where.wall];
      if (w) { anchor = w.points[where.point === undefined ? 0 : Math.min(where.point, w.points.length - 1)]; }
    } else if (where === 'finish') { anchor = model.finish.a; }
    else if (where === 'start') { anchor = model.start.position; }
    var box = $('edit-error');
    box.textContent = message;
    box.hidden = false;
    var at = anchor ? inView(toScreen(anchor)) : [16, 16];
    var vw = $('view').clientWidth;
    box.style.left = Math.max(4, Math.min(at[0] + 14, vw - box.offsetWidth - 4)) + 'px';
    box.style.top = Math.max(4, at[1] + 14) + 'px';
  }

  // ---- solving ----
  function progressShow(text, fraction, busy) {
    $('progress').className = busy ? 'busy' : 'idle';
    $('progress-text').textContent = text;
    $('progress-fill').style.width = (100 * Math.min(1, Math.max(0, fraction))) + '%';
  }

  function pollProgress() {
    fetch('/api/progress').then(function (r) { return r.json(); }).then(function (p) {
      if (!waiting) { return; }
      if (p.running) {
        progressShow('solving edit ' + p.id + ': ' + p.stage + ' (' + p.elapsed_s.toFixed(1) + ' s of ' + timeLimit + ' s)',
          p.elapsed_s / timeLimit, true);
      } else {
        progressShow('waiting for the solver', 0, true);
      }
    }).catch(function () {});
  }

  function edit(where) {
    var body = JSON.stringify({ scene: model, quality: quality });
    var mine = ++sent;
    waiting += 1;
    $('results').classList.add('stale');
    if (!progressTimer) { progressTimer = setInterval(pollProgress, 200); }
    progressShow('sending the edit', 0, true);
    fetch('/api/solve', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: body })
      .then(function (r) { return r.json().catch(function () { return { status: 'error', error: 'HTTP ' + r.status }; }); })
      .then(function (answer) { answered(answer, mine, where, body); })
      .catch(function (err) { answered({ status: 'error', error: 'the server did not answer: ' + err.message }, mine, where, body); });
  }

  function answered(answer, mine, where, body) {
    waiting -= 1;
    if (waiting === 0 && progressTimer) { clearInterval(progressTimer); progressTimer = null; }
    if (answer.status === 'solved') {
      // The server solves edits in order: a newer result is never replaced by an older one.
      if (!result || answer.id > result.id) {
        result = answer;
        solvedModel = JSON.parse(body).scene;
        drawResult(); drawTable();
      }
      if (mine === sent) {
        bad = null; hideError();
        $('results').classList.remove('stale');
        $('result-note').textContent = '';
        $('revert').disabled = true;
        drawScene();
      }
      progressShow(waiting ? 'solving' : 'solved in ' + answer.summary.solve_seconds.toFixed(2) + ' s', 1, waiting > 0);
      return;
    }
    if (answer.status === 'superseded') { return; }
    if (mine !== sent) { return; }
    showError(where, answer.error || 'the edit was refused');
    $('result-note').textContent = '(of the last solved scene)';
    $('revert').disabled = !solvedModel;
    progressShow(answer.status === 'no-path' ? 'no valid path' : 'edit refused', 0, false);
  }

  function drawAll() { drawGrid(); drawScene(); drawResult(); }

  fetch('/api/scene').then(function (r) { return r.json(); }).then(function (init) {
    model = init.scene;
    quality = init.quality;
    timeLimit = init.time_limit_s;
    fit();
    drawAll();
    edit('quality');
  }).catch(function (err) { progressShow('cannot load the scene: ' + err.message, 0, false); });
}());
