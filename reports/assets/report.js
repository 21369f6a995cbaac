// The pages' behaviour, in plain JavaScript (no network, nothing loaded from elsewhere).
// index.html: tables sorted by clicking a header (numbers as numbers, "n/a" last) and
// filtered by a text box. Run pages: a comparison view with zoom (wheel, + and -), pan (drag)
// and flipping between images (buttons, arrows or n/p, f flips back to this run), or swiping
// between this run and another (s: this run left of the pointer, the other right of it).
// A run in motion's page also has three players (method, reference, error map) driven by one
// play/pause button and one frame slider, always on the same frame; playing advances a frame
// every frame delay and loops.
// Every page marks each image's data-loaded attribute (yes or no) once loaded; opened with
// #selftest it exercises itself (it sorts and filters the first table of runs, and sorts every
// other sortable table) and writes what it found into a pre element of id selftest, one
// "key: value" line each, for a headless browser's --dump-dom. On index.html the
// self-test first checks the layout in a window of 1400 x 1000 pixels: whether the first
// screen (nothing scrolled) holds the Pareto summary (#summary) and the machine line
// (#measured), and whether any table of runs is wider than the window or its container.
(function () {
  'use strict';

  function cellValue(td) {
    var v = td.getAttribute('data-v');
    if (v !== null && v !== '') return parseFloat(v);
    var t = td.textContent.trim();
    return /^[-+]?[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?/.test(t) ? parseFloat(t) : t;
  }

  function compare(a, b, dir) {
    var na = typeof a === 'number', nb = typeof b === 'number';
    if (na && nb) return dir * (a - b);
    if (na) return -1; // numbers before text ("n/a", empty) in either direction
    if (nb) return 1;
    return dir * String(a).localeCompare(String(b), undefined, {numeric: true});
  }

  function sortTable(table, col, dir) {
    var body = table.tBodies[0];
    var rows = Array.prototype.slice.call(body.rows);
    rows.sort(function (r, s) {
      return compare(cellValue(r.cells[col]), cellValue(s.cells[col]), dir);
    });
    rows.forEach(function (r) { body.appendChild(r); });
    var heads = table.tHead.rows[0].cells;
    for (var i = 0; i < heads.length; i++) {
      heads[i].setAttribute('aria-sort', i === col ? (dir > 0 ? 'ascending' : 'descending') : 'none');
    }
  }

  function clickSort(table, col) {
    var th = table.tHead.rows[0].cells[col];
    sortTable(table, col, th.getAttribute('aria-sort') === 'ascending' ? -1 : 1);
  }

  function filterTable(table, text) {
    var words = text.toLowerCase().split(/\s+/).filter(Boolean);
    var rows = table.tBodies[0].rows, shown = 0;
    for (var i = 0; i < rows.length; i++) {
      var t = rows[i].textContent.toLowerCase();
      var keep = words.every(function (w) { return t.indexOf(w) >= 0; });
      rows[i].style.display = keep ? '' : 'none';
      shown += keep ? 1 : 0;
    }
    return shown;
  }

  function setupTables() {
    document.querySelectorAll('table.sortable').forEach(function (table) {
      var heads = table.tHead.rows[0].cells;
      Array.prototype.forEach.call(heads, function (th, col) {
        th.tabIndex = 0;
        th.title = 'sort by this column';
        th.addEventListener('click', function () { clickSort(table, col); });
        th.addEventListener('keydown', function (e) {
          if (e.key === 'Enter') clickSort(table, col);
        });
      });
      var box = table.previousElementSibling;
      if (box && box.classList.contains('filter')) {
        box.addEventListener('input', function () { filterTable(table, box.value); });
      }
    });
  }

  // The comparison view of a run page.
  function setupViewer() {
    var viewer = document.getElementById('viewer');
    if (!viewer) return null;
    var stage = viewer.querySelector('.stage');
    var views = Array.prototype.slice.call(stage.querySelectorAll('img.view'));
    var select = document.getElementById('view-select');
    var label = document.getElementById('view-label');
    var st = {scale: 1, x: 0, y: 0, active: 0, other: views.length > 1 ? 1 : 0,
      swipe: false, split: 0.5};
    function apply() {
      stage.style.transform = 'translate(' + st.x + 'px,' + st.y + 'px) scale(' + st.scale + ')';
    }
    function fit() {
      var img = views[st.active];
      var w = img.naturalWidth || 1, h = img.naturalHeight || 1;
      st.scale = Math.min(viewer.clientWidth / w, viewer.clientHeight / h);
      st.x = (viewer.clientWidth - w * st.scale) / 2;
      st.y = (viewer.clientHeight - h * st.scale) / 2;
      apply();
    }
    // Shows the active view; in swipe mode, this run left of the split and the other view
    // right of it, laid over it.
    function render() {
      views.forEach(function (img, k) {
        var over = st.swipe && k === st.other && k !== 0;
        img.classList.toggle('active', st.swipe ? k === 0 || over : k === st.active);
        img.classList.toggle('overlay', over);
        img.style.clipPath = over ? 'inset(0 0 0 ' + (100 * st.split).toFixed(2) + '%)' : '';
      });
      var k = st.swipe ? st.other : st.active;
      select.value = String(k);
      label.textContent = st.swipe
        ? 'left: this run, right: ' + views[st.other].getAttribute('data-label')
        : views[k].getAttribute('data-label');
    }
    function show(k) {
      k = (k + views.length) % views.length;
      st.active = k;
      if (k !== 0) st.other = k;
      render();
    }
    function swipe() {
      st.swipe = !st.swipe && views.length > 1;
      render();
    }
    function zoom(factor, cx, cy) {
      st.x = cx - (cx - st.x) * factor;
      st.y = cy - (cy - st.y) * factor;
      st.scale *= factor;
      apply();
    }
    viewer.addEventListener('wheel', function (e) {
      e.preventDefault();
      var r = viewer.getBoundingClientRect();
      zoom(e.deltaY < 0 ? 1.25 : 0.8, e.clientX - r.left, e.clientY - r.top);
    }, {passive: false});
    var drag = null;
    viewer.addEventListener('mousedown', function (e) {
      drag = {x: e.clientX - st.x, y: e.clientY - st.y};
      viewer.focus();
      e.preventDefault();
    });
    viewer.addEventListener('mousemove', function (e) {
      if (drag || !st.swipe) return;
      var r = viewer.getBoundingClientRect(), w = views[0].naturalWidth * st.scale;
      st.split = Math.min(1, Math.max(0, (e.clientX - r.left - st.x) / (w || 1)));
      render();
    });
    window.addEventListener('mousemove', function (e) {
      if (!drag) return;
      st.x = e.clientX - drag.x;
      st.y = e.clientY - drag.y;
      apply();
    });
    window.addEventListener('mouseup', function () { drag = null; });
    function flip() { show(st.active === 0 ? st.other : 0); }
    document.addEventListener('keydown', function (e) {
      if (e.target.tagName === 'SELECT' || e.target.tagName === 'INPUT') return;
      var c = viewer.clientWidth / 2, m = viewer.clientHeight / 2;
      switch (e.key) {
        case 'ArrowRight': case 'n': show(st.active + 1); break;
        case 'ArrowLeft': case 'p': show(st.active - 1); break;
        case 'f': case ' ': flip(); break;
        case 's': swipe(); break;
        case '+': case '=': zoom(1.25, c, m); break;
        case '-': zoom(0.8, c, m); break;
        case '0': fit(); break;
        default: return;
      }
      e.preventDefault();
    });
    document.getElementById('prev').addEventListener('click', function () { show(st.active - 1); });
    document.getElementById('next').addEventListener('click', function () { show(st.active + 1); });
    document.getElementById('flip').addEventListener('click', flip);
    document.getElementById('fit').addEventListener('click', fit);
    document.getElementById('swipe').addEventListener('click', swipe);
    select.addEventListener('change', function () { show(parseInt(select.value, 10)); });
    // `#view=N` opens the page on view N (0: this run, 1: the reference, 2: the error map).
    var m = /^#view=(\d+)$/.exec(location.hash);
    show(m ? parseInt(m[1], 10) : 0);
    return {state: st, views: views, fit: fit, viewer: viewer};
  }

  // The players of a run in motion: every image of #players shows frame k of its kind
  // (data-kind) as BASE + KIND-NNNN.png; the slider sets k, playing advances it every
  // data-frame-ms milliseconds, from the last frame back to the first. Each frame's three
  // images are fetched ahead of it while playing.
  function frameName(base, kind, k) {
    var s = String(k);
    while (s.length < 4) s = '0' + s;
    return base + kind + '-' + s + '.png';
  }

  function frameOf(src) {
    var m = /-(\d{4,})\.png$/.exec(src || '');
    return m ? parseInt(m[1], 10) : -1;
  }

  function setupPlayers() {
    var box = document.getElementById('players');
    if (!box) return null;
    var imgs = Array.prototype.slice.call(box.querySelectorAll('img.player'));
    var n = Math.max(1, parseInt(box.getAttribute('data-frames'), 10) || 1);
    var delay = Math.max(10, parseInt(box.getAttribute('data-frame-ms'), 10) || 100);
    var base = box.getAttribute('data-base');
    var times = (box.getAttribute('data-times') || '').split(' ');
    var slider = document.getElementById('frame-slider');
    var counter = document.getElementById('frame-counter');
    var button = document.getElementById('play');
    var rows = Array.prototype.slice.call(document.querySelectorAll('#frame-table tbody tr'));
    var st = {frame: 0, timer: null};
    var ahead = [];
    function show(k) {
      k = ((k % n) + n) % n;
      st.frame = k;
      imgs.forEach(function (img) {
        img.setAttribute('src', frameName(base, img.getAttribute('data-kind'), k));
      });
      slider.value = String(k);
      counter.textContent = 'frame ' + k + ' / ' + n + (times[k] ? ', t = ' + times[k] : '');
      rows.forEach(function (r) {
        r.classList.toggle('current', r.getAttribute('data-frame') === String(k));
      });
      if (st.timer !== null) {
        ahead = imgs.map(function (img) {
          var next = new Image();
          next.src = frameName(base, img.getAttribute('data-kind'), (k + 1) % n);
          return next;
        });
      }
    }
    function play() {
      if (st.timer !== null) return;
      st.timer = setInterval(function () { show(st.frame + 1); }, delay);
      button.textContent = 'pause';
    }
    function pause() {
      if (st.timer === null) return;
      clearInterval(st.timer);
      st.timer = null;
      button.textContent = 'play';
    }
    button.addEventListener('click', function () {
      if (st.timer === null) play(); else pause();
    });
    slider.addEventListener('input', function () { show(parseInt(slider.value, 10)); });
    show(0);
    return {state: st, imgs: imgs, slider: slider, button: button, frames: n, delay: delay,
      ahead: function () { return ahead.length; }};
  }

  // The players' findings: the slider moves all three images to its frame; playing advances
  // them, in step; playing on from the last frame loops back to the first. Calls done when
  // it has written them into out.
  function playersTest(p, out, done) {
    function shown() {
      return p.imgs.map(function (i) { return frameOf(i.getAttribute('src')); });
    }
    function same(k) {
      return p.imgs.length === 3 && shown().every(function (f) { return f === k; }) &&
        parseInt(p.slider.value, 10) === k && p.state.frame === k;
    }
    function slide(k) {
      p.slider.value = String(k);
      p.slider.dispatchEvent(new Event('input', {bubbles: true}));
    }
    var target = Math.min(3, p.frames - 1);
    slide(target);
    out.push('players: slider ' + target + ' -> ' + shown().join(' ') + ' ' +
      (same(target) ? 'ok' : 'FAILED'));
    if (p.frames < 2) {
      out.push('players: one frame, nothing to play');
      done();
      return;
    }
    slide(0);
    p.button.click();
    setTimeout(function () {
      var playing = p.button.textContent === 'pause';
      p.button.click();
      var k = p.state.frame, sync = same(k);
      out.push('players: play advanced 0 -> ' + k + ', ' + (sync ? 'in sync' : 'out of sync: ' +
        shown().join(' ')) + (playing && k !== 0 && sync && p.ahead() === 3 ? ' ok' : ' FAILED'));
      var last = p.frames - 1;
      slide(last);
      p.button.click();
      setTimeout(function () {
        p.button.click();
        var j = p.state.frame;
        out.push('players: loop ' + last + ' -> ' + j + ' ' + (j < last && same(j) ? 'ok' : 'FAILED'));
        done();
      }, 1.5 * p.delay);
    }, 3.5 * p.delay);
  }

  // The layout findings of index.html: "first screen" and "runs tables", each "ok" or
  // "FAILED" with what was measured.
  var SCREEN = {width: 1400, height: 1000};
  function layout(out) {
    var tables = Array.prototype.slice.call(document.querySelectorAll('table.runs'));
    if (!tables.length) return;
    out.push('viewport: ' + window.innerWidth + 'x' + window.innerHeight);
    function box(id) {
      var el = document.getElementById(id);
      if (!el) return null;
      var r = el.getBoundingClientRect();
      return {top: r.top + window.scrollY, bottom: r.bottom + window.scrollY,
        right: r.right + window.scrollX};
    }
    function within(b) {
      return b !== null && b.top >= 0 && b.bottom <= SCREEN.height && b.right <= SCREEN.width;
    }
    function where(name, b) {
      return name + (b === null ? ' missing' : ' ' + Math.round(b.top) + '-' +
        Math.round(b.bottom) + ' px');
    }
    var summary = box('summary'), machine = box('measured');
    out.push('first screen: ' + (within(summary) && within(machine) ? 'ok' : 'FAILED') + ' (' +
      where('Pareto summary', summary) + ', ' + where('machine line', machine) + ', in the top ' +
      SCREEN.height + ' px)');
    var page = document.documentElement.scrollWidth, wide = [], widest = 0, time = null;
    tables.forEach(function (t) {
      var room = t.parentElement.clientWidth, r = t.getBoundingClientRect();
      widest = Math.max(widest, t.scrollWidth);
      if (t.scrollWidth > room || r.right + window.scrollX > SCREEN.width) {
        wide.push(t.scrollWidth + ' in ' + room);
      }
      Array.prototype.forEach.call(t.tHead.rows[0].cells, function (th) {
        if (/\b(CPU|wall) ms\b/.test(th.textContent)) {
          time = Math.max(time || 0, th.getBoundingClientRect().right + window.scrollX);
        }
      });
    });
    var ok = page <= SCREEN.width && wide.length === 0 && time !== null && time <= SCREEN.width;
    // Where each scene's runs heading starts, for a screenshot of a runs table.
    out.push('runs headings: ' + Array.prototype.map.call(
      document.querySelectorAll('h3[id$="-runs"]'), function (h) {
        return h.id + ' ' + Math.round(h.getBoundingClientRect().top + window.scrollY);
      }).join(', '));
    out.push('runs tables: ' + (ok ? 'ok' : 'FAILED') + ' (page ' + page + ' px wide; ' +
      tables.length + ' tables, the widest ' + widest + ' px; time columns end at ' +
      (time === null ? 'none' : Math.round(time) + ' px') +
      (wide.length ? '; wider than their container: ' + wide.join(', ') : '') + ')');
  }

  function selftest(v, players) {
    var out = [];
    layout(out);
    var images = Array.prototype.slice.call(document.images);
    var bad = images.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
    out.push('images: ' + (images.length - bad.length) + ' of ' + images.length + ' loaded');
    bad.forEach(function (i) { out.push('broken image: ' + i.getAttribute('src')); });
    // The first numeric column of a table, and its numbers in the order shown.
    function numericColumn(t) {
      return Array.prototype.findIndex.call(t.tHead.rows[0].cells, function (th) {
        return th.classList.contains('num');
      });
    }
    function values(t, col) {
      return Array.prototype.map.call(t.tBodies[0].rows, function (r) {
        return cellValue(r.cells[col]);
      }).filter(function (x) { return typeof x === 'number'; });
    }
    function ordered(t, col, dir) {
      var xs = values(t, col);
      for (var i = 1; i < xs.length; i++) if (dir * (xs[i] - xs[i - 1]) < 0) return false;
      return xs.length > 1;
    }
    var table = document.querySelector('table.runs') || document.querySelector('table.sortable');
    if (table) {
      var col = numericColumn(table);
      var before = values(table, col).join(' ');
      clickSort(table, col);
      var up = ordered(table, col, 1), upValues = values(table, col).join(' ');
      clickSort(table, col);
      var down = ordered(table, col, -1);
      out.push('sort column: ' + table.tHead.rows[0].cells[col].textContent);
      out.push('sort: ' + (up && down ? 'ok' : 'FAILED') + ' (before ' + before + '; ascending ' +
        upValues + '; descending ' + values(table, col).join(' ') + ')');
      var first = table.tBodies[0].rows[0].cells[0].textContent.trim();
      var total = table.tBodies[0].rows.length;
      var shown = filterTable(table, first);
      var none = filterTable(table, 'no row holds this text');
      filterTable(table, '');
      out.push('filter: ' + (shown >= 1 && shown <= total && none === 0 ? 'ok' : 'FAILED') +
        ' (' + shown + ' of ' + total + ' rows hold "' + first + '")');
    }
    // Every other sortable table with two numbers in a numeric column sorts by its first,
    // ascending then descending; the finding names them by their class.
    var sorted = [], unsorted = [];
    document.querySelectorAll('table.sortable').forEach(function (t) {
      var c = numericColumn(t);
      if (t === table || c < 0 || values(t, c).length < 2) return;
      clickSort(t, c);
      var ascending = ordered(t, c, 1);
      clickSort(t, c);
      var name = t.classList.length > 1 ? t.classList[1] : 'sortable';
      (ascending && ordered(t, c, -1) ? sorted : unsorted).push(name);
    });
    out.push('sort tables: ' + (unsorted.length ? 'FAILED for ' + unsorted.join(', ') : 'ok') +
      ' (' + sorted.join(', ') + ')');
    if (v) {
      var st = v.state, start = st.active;
      var src = function () { return v.views[st.active].getAttribute('src'); };
      var a = src();
      document.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowRight', bubbles: true}));
      var b = src();
      document.getElementById('flip').click();
      var c = src();
      out.push('views: ' + v.views.length);
      out.push('flip: ' + (v.views.length > 1 && a !== b && c === a && start === 0 ? 'ok' : 'FAILED') +
        ' (' + a + ' -> ' + b + ' -> ' + c + ')');
      var s0 = st.scale, r = v.viewer.getBoundingClientRect();
      v.viewer.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, clientX: r.left + 10,
        clientY: r.top + 10, bubbles: true, cancelable: true}));
      var zoomed = st.scale > s0;
      var x0 = st.x;
      v.viewer.dispatchEvent(new MouseEvent('mousedown', {clientX: 50, clientY: 50, bubbles: true}));
      window.dispatchEvent(new MouseEvent('mousemove', {clientX: 80, clientY: 60}));
      window.dispatchEvent(new MouseEvent('mouseup', {}));
      var panned = Math.abs(st.x - x0 - 30) < 1e-6;
      out.push('zoom and pan: ' + (zoomed && panned ? 'ok' : 'FAILED'));
      var shown = function () {
        return v.views.filter(function (i) { return getComputedStyle(i).display !== 'none'; });
      };
      var single = shown().length;
      document.getElementById('swipe').click();
      var two = shown(), clip = two.length === 2 ? getComputedStyle(two[1]).clipPath : '';
      document.getElementById('swipe').click();
      out.push('swipe: ' + (single === 1 && two.length === 2 && two[0] === v.views[0] &&
        /inset/.test(clip) && shown().length === 1 ? 'ok' : 'FAILED') + ' (' + single + ', ' +
        two.length + ' images shown, ' + clip + ')');
    }
    document.querySelectorAll('a[href]').forEach(function (l) {
      var h = l.getAttribute('href');
      if (!/^(#|[a-z]+:)/i.test(h)) out.push('link: ' + h.split('#')[0]);
    });
    function write() {
      var pre = document.createElement('pre');
      pre.id = 'selftest';
      pre.textContent = out.join('\n');
      document.body.appendChild(pre);
    }
    if (players) playersTest(players, out, write); else write();
  }

  window.addEventListener('load', function () {
    for (var k = 0; k < document.images.length; k++) {
      var i = document.images[k];
      i.setAttribute('data-loaded', i.complete && i.naturalWidth > 0 ? 'yes' : 'no');
    }
    setupTables();
    var v = setupViewer();
    if (v) v.fit();
    var players = setupPlayers();
    if (location.hash === '#selftest') selftest(v, players);
    document.body.setAttribute('data-checked', 'yes');
  });
})();
