// ptview -serve: the page. State, controls, the server's data and the live
// diffusion; drawing is viewer_gl.js's. Everything it loads comes from the
// server that sent it (docs/ptview.md, "Interactive view").
'use strict';

(() => {
  const $ = (id) => document.getElementById(id);
  const GAP = 2;

  // What tests and scripts read (tests/browser/browser_test.py).
  const view = (window.sssView = {
    ready: false, errors: [], latencies: [], renders: 0, busy: 0,
    shownHash: '', liveSeq: 0, shownLiveSeq: 0, exposure: 0, batchCommand: '',
  });
  function fail(message) {
    view.errors.push(String(message));
    setStatus(String(message), true);
  }
  window.addEventListener('error', (e) => fail(e.message));
  window.addEventListener('unhandledrejection', (e) => fail(e.reason && e.reason.message ? e.reason.message : e.reason));

  function setStatus(text, error = false) {
    const s = $('status');
    s.textContent = text;
    s.className = error ? 'error' : '';
  }

  // --- the server's answers ----------------------------------------------------
  async function fetchOk(url, options) {
    const r = await fetch(url, options);
    if (!r.ok) throw new Error((await r.text()).trim() || 'HTTP ' + r.status);
    return r;
  }
  // A binary answer: uint32 JSON length, the JSON, padding to 4, float32s.
  async function fetchFloats(url, options) {
    const buf = await (await fetchOk(url, options)).arrayBuffer();
    const n = new DataView(buf).getUint32(0, true);
    const meta = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
    const start = (4 + n + 3) & ~3;
    return { meta, floats: new Float32Array(buf, start, (buf.byteLength - start) / 4) };
  }
  // FNV-1a of the floats' bytes, as the server's value_hash().
  function hashFloats(floats) {
    const bytes = new Uint8Array(floats.buffer, floats.byteOffset, floats.byteLength);
    let h = 0x811c9dc5;
    for (let i = 0; i < bytes.length; ++i) h = Math.imul(h ^ bytes[i], 0x01000193);
    return (h >>> 0).toString(16).padStart(8, '0');
  }
  const fmt = (x) => String(Number(Number(x).toPrecision(4)));
  // A command line shown: lines break between its words only (its text, as
  // copied, is unchanged).
  function showCommand(element, text) {
    element.textContent = '';
    text.split(' ').forEach((word, i) => {
      if (i) element.appendChild(document.createTextNode(' '));
      const span = document.createElement('span');
      span.className = 'word';
      span.textContent = word;
      element.appendChild(span);
    });
  }

  // --- state --------------------------------------------------------------------
  const S = {
    scene: null, tiles: [], layout: 'side', camera: 'auto', az: 30, el: 20, up: 1, fov: 30,
    zoom: 1, panX: 0, panY: 0, res: 'fit', exposure: 'auto', falseColour: true,
    radiusScale: 1, background: [0.05, 0.05, 0.05], voxelShape: 'square', showLive: true,
    live: null, // {cloud, preset, albedo, dmfp, scale, unitlength, profile, volume, name}
  };

  function readHash() {
    const h = {};
    for (const part of location.hash.replace(/^#/, '').split('&')) {
      const eq = part.indexOf('=');
      if (eq > 0) h[decodeURIComponent(part.slice(0, eq))] = decodeURIComponent(part.slice(eq + 1));
    }
    const num = (k, lo, hi) => {
      const v = Number(h[k]);
      return k in h && Number.isFinite(v) && v >= lo && v <= hi ? v : undefined;
    };
    if (num('az', -1e6, 1e6) !== undefined) S.az = num('az', -1e6, 1e6);
    if (num('el', -90, 90) !== undefined) S.el = num('el', -90, 90);
    if (h.up && 'xyz'.includes(h.up) && h.up.length === 1) S.up = 'xyz'.indexOf(h.up);
    if (num('fov', 0.1, 169.9) !== undefined) S.fov = num('fov', 0.1, 169.9);
    if (h.camera === 'orbit' || h.camera === 'file') S.camera = h.camera;
    const res = /^(\d{1,4})x(\d{1,4})$/.exec(h.res || '');
    if (res && +res[1] > 0 && +res[2] > 0) S.res = [+res[1], +res[2]];
    if (h.exposure === 'tile' || h.exposure === 'auto') S.exposure = h.exposure;
    else if (num('exposure', -256, 256) !== undefined) S.exposure = num('exposure', -256, 256);
    if (h.falsecolor === '0' || h.falsecolor === '1') S.falseColour = h.falsecolor === '1';
    if (num('radiusscale', 1e-6, 1e6) !== undefined) S.radiusScale = num('radiusscale', 1e-6, 1e6);
    const bg = (h.background || '').split(',').map(Number);
    if (bg.length === 3 && bg.every((x) => Number.isFinite(x) && x >= 0)) S.background = bg;
    if (h.layout === 'overlay' || h.layout === 'side') S.layout = h.layout;
    if (h.live === '0') S.showLive = false;
    return h;
  }
  function writeHash() {
    const parts = [`az=${fmt(S.az)}`, `el=${fmt(S.el)}`, `up=${'xyz'[S.up]}`, `fov=${fmt(S.fov)}`,
      `camera=${cameraKind()}`, `exposure=${typeof S.exposure === 'number' ? fmt(S.exposure) : S.exposure}`,
      `falsecolor=${S.falseColour ? 1 : 0}`, `radiusscale=${fmt(S.radiusScale)}`, `layout=${S.layout}`];
    if (S.res !== 'fit') parts.push(`res=${S.res[0]}x${S.res[1]}`);
    if (!S.showLive) parts.push('live=0');
    history.replaceState(null, '', '#' + parts.join('&'));
  }

  // --- sources: what each tile draws --------------------------------------------
  const inputOf = (i) => S.scene.inputs[i];
  function channelsOf(tile) {
    const list = tile.kind === 'live' ? [{ name: '_ssdiffusion', type: 'color', components: 3 }]
      : inputOf(tile.input).channels.filter((c) => c.type !== 'matrix');
    return list;
  }
  function defaultChannel(input) {
    const cs = input.channels;
    const colour = cs.find((c) => c.type === 'color');
    if (colour) return colour.name;
    const any = cs.find((c) => c.type !== 'matrix');
    return any ? any.name : 'N';
  }
  function sourceId(tile) {
    if (tile.kind === 'brick') return `b${tile.input}.${tile.depth}`;
    return `c${tile.input}`;
  }
  function tileLabel(tile) {
    const input = inputOf(tile.input);
    let text = input.label;
    if (tile.kind === 'brick') text += ` depth ${tile.depth}`;
    if (tile.kind === 'live') text += ' live diffusion';
    return `${text} · ${tile.channel}${tile.lum ? ':lum' : ''}`;
  }
  // The tiles of a channel list, ptview's rule: each file shows each listed
  // channel it has (N and radius: every file), in the order listed.
  function initialTiles(hash) {
    const wanted = hash.channel ? hash.channel.split(',').filter((x) => x) : [];
    const tiles = [];
    for (const input of S.scene.inputs) {
      const kind = input.kind === 'brickmap' ? 'brick' : 'cloud';
      const base = { kind, input: input.index, visible: true, depth: input.surface_depth || 0 };
      const names = input.channels.map((c) => c.name).concat(['N', 'radius']);
      const listed = wanted.map((w) => ({ name: w.replace(/:lum$/, ''), lum: w.endsWith(':lum') }))
        .filter((c) => names.includes(c.name));
      if (wanted.length === 0) tiles.push({ ...base, channel: defaultChannel(input), lum: false });
      for (const c of listed) tiles.push({ ...base, channel: c.name, lum: c.lum });
      if (input.live) tiles.push({ kind: 'live', input: input.index, visible: S.showLive, channel: '_ssdiffusion', lum: false });
    }
    return tiles;
  }

  // GPU data of sources, loaded once: geometry (positions, normals, radii) and
  // channels, by source id.
  const gpu = new Map();
  let renderer = null;
  async function loadGeometry(id) {
    if (gpu.has(id)) return gpu.get(id);
    const entry = { loading: true, channels: new Map() };
    gpu.set(id, entry);
    view.busy++;
    try {
      const { floats } = await fetchFloats(`/api/data/${id}/geometry`);
      const n = floats.length / 7;
      entry.n = n;
      entry.cpu = floats;
      entry.pos = renderer.buffer(floats.subarray(0, 3 * n));
      entry.nrm = renderer.buffer(floats.subarray(3 * n, 6 * n));
      entry.rad = renderer.buffer(floats.subarray(6 * n));
      entry.loading = false;
    } finally { view.busy--; }
    return entry;
  }
  async function loadChannel(id, k) {
    const entry = await loadGeometry(id);
    if (entry.channels.has(k)) return entry.channels.get(k);
    view.busy++;
    try {
      const { floats } = await fetchFloats(`/api/data/${id}/channel/${k}`);
      const c = { buf: renderer.buffer(floats), comps: floats.length / Math.max(1, entry.n) };
      entry.channels.set(k, c);
      return c;
    } finally { view.busy--; }
  }
  function channelMode(channel, lum) {
    if (!channel) return 0;
    if (channel.type === 'float') return 0;
    if (lum) return 2;
    return channel.type === 'normal' ? 3 : 1;
  }
  // The layer a tile draws, or null while its data is missing.
  function layerOf(tile) {
    const geo = gpu.get(sourceId(tile));
    if (!geo || geo.loading) return null;
    const layer = { n: geo.n, pos: geo.pos, nrm: geo.nrm, rad: geo.rad, square: tile.kind === 'brick' && S.voxelShape === 'square' };
    const live = tile.kind === 'live' ? liveShown[tile.input] : null;
    if (tile.kind === 'live') {
      if (!live) return null;
      if (live.stride > 1) Object.assign(layer, subsampleOf(tile.input, live.stride));
    }
    if (tile.channel === 'N') return { ...layer, mode: 4 };
    if (tile.channel === 'radius') return { ...layer, mode: 5 };
    if (live) return { ...layer, val: live.buf, comps: 3, mode: tile.lum ? 2 : 1, keepIndex: live.stride > 1 };
    const list = inputOf(tile.input).channels;
    const k = list.findIndex((c) => c.name === tile.channel);
    const c = geo.channels.get(k);
    if (!c) return null;
    return { ...layer, val: c.buf, comps: c.comps, mode: channelMode(list[k], tile.lum) };
  }
  async function loadTile(tile) {
    await loadGeometry(sourceId(tile));
    if (tile.kind === 'live' || tile.channel === 'N' || tile.channel === 'radius') return;
    const k = inputOf(tile.input).channels.findIndex((c) => c.name === tile.channel);
    if (k >= 0) await loadChannel(sourceId(tile), k);
  }

  // The live diffusion's subsample: every stride-th point, radius times
  // sqrt(stride), as the server computes it (view_session.cpp).
  const subsamples = new Map();
  function subsampleOf(input, stride) {
    const key = `${input}/${stride}`;
    if (subsamples.has(key)) return subsamples.get(key);
    const geo = gpu.get(`c${input}`), n = geo.n, m = Math.ceil(n / stride), g = geo.cpu;
    const pos = new Float32Array(3 * m), nrm = new Float32Array(3 * m), rad = new Float32Array(m);
    const grow = Math.fround(Math.sqrt(stride));
    for (let j = 0; j < m; ++j) {
      const i = j * stride;
      for (let k = 0; k < 3; ++k) { pos[3 * j + k] = g[3 * i + k]; nrm[3 * j + k] = g[3 * n + 3 * i + k]; }
      rad[j] = Math.fround(g[6 * n + i] * grow);
    }
    const s = { n: m, pos: renderer.buffer(pos), nrm: renderer.buffer(nrm), rad: renderer.buffer(rad) };
    subsamples.set(key, s);
    return s;
  }

  // --- layout and cameras ---------------------------------------------------------
  function cameraKind() {
    const first = S.tiles.find((t) => t.visible);
    const has = first && inputOf(first.input).camera;
    if (S.camera === 'file' && has) return 'file';
    if (S.camera === 'auto' && has) return 'file';
    return 'orbit';
  }
  function unionBounds(tiles) {
    let b = null;
    for (const t of tiles) {
      const x = inputOf(t.input).bounds;
      b = b ? [Math.min(b[0], x[0]), Math.min(b[1], x[1]), Math.min(b[2], x[2]), Math.max(b[3], x[3]), Math.max(b[4], x[4]), Math.max(b[5], x[5])] : x.slice();
    }
    return b || [-1, -1, -1, 1, 1, 1];
  }
  function tileSize(count, columns, rows, first) {
    if (S.res !== 'fit') return S.res;
    const stage = $('stage');
    const w = Math.max(64, Math.floor((stage.clientWidth - 8 - GAP * (columns - 1)) / columns));
    const h = Math.max(64, Math.floor((stage.clientHeight - 8 - GAP * (rows - 1)) / rows));
    if (cameraKind() === 'file') {
      const aspect = SssGl.fileAspect(inputOf(first.input).camera.format);
      return w / h > aspect ? [Math.max(1, Math.round(h * aspect)), h] : [w, Math.max(1, Math.round(w / aspect))];
    }
    return [w, h];
  }
  // The sheet: tiles laid out as ptview's contact sheets, one camera.
  function layout() {
    const shown = S.tiles.filter((t) => t.visible);
    const groups = S.layout === 'overlay' && shown.length ? [shown] : shown.map((t) => [t]);
    const count = Math.max(1, groups.length);
    const columns = count <= 4 ? count : Math.ceil(Math.sqrt(count) - 1e-9);
    const rows = Math.ceil(count / columns);
    const [w, h] = tileSize(count, columns, rows, shown[0]);
    const bounds = unionBounds(shown);
    const camera = cameraKind() === 'file' ? SssGl.fileCamera(inputOf(shown[0].input).camera, w, h)
      : SssGl.orbitCamera(bounds, S.az, S.el, S.up, S.fov, w, h, S.zoom, S.panX, S.panY);
    const depth = SssGl.depthRange(camera, bounds);
    const sheet = groups.map((g, i) => ({
      members: g, camera, depth, x: (i % columns) * (w + GAP), y: Math.floor(i / columns) * (h + GAP),
    }));
    return { sheet, width: columns * w + (columns - 1) * GAP, height: rows * h + (rows - 1) * GAP };
  }

  // --- drawing ---------------------------------------------------------------------
  let exposureStops = [];
  let exposureDirty = true;
  let dragging = false;
  let lastKey = '';
  let indexKey = []; // per tile: the key of the view its index region was drawn in
  // Draws the sheet; `changed` (an input index): only that input's live
  // diffusion changed, so when nothing else did, only its tiles are drawn
  // again (the others keep their values); 'display': only the exposure or
  // false colour changed, no tile is drawn again.
  function render(changed = null) {
    if (!renderer || !S.scene) return;
    // Fitted to the window, the sheet never needs scroll bars (which would
    // change the room it is fitted to).
    $('stage').style.overflow = S.res === 'fit' ? 'hidden' : 'auto';
    const { sheet, width, height } = layout();
    renderer.resize(Math.max(1, width), Math.max(1, height));
    const tiles = sheet.map((t) => ({ ...t, layers: t.members.map(layerOf).filter((l) => l) }));
    const key = JSON.stringify([width, height, Array.from(sheet[0] ? sheet[0].camera.raster : []),
      S.tiles.map((t) => [t.visible, t.channel, t.lum, t.depth]), S.radiusScale, S.voxelShape, S.layout,
      tiles.map((t) => t.layers.length)]);
    let only = null, resolve = [];
    if (changed === 'display' && key === lastKey) only = [];
    else if (changed !== null && key === lastKey) {
      only = sheet.map((t, i) => (t.members.some((m) => m.kind === 'live' && m.input === changed) ? i : -1)).filter((i) => i >= 0);
      // A whole result in a view whose points are drawn already: new values
      // at the pixels, no point drawn again.
      const live = liveShown[changed];
      resolve = only.filter((i) => live && live.tex && indexKey[i] === key && tiles[i].layers.length === 1 &&
                                   !tiles[i].layers[0].keepIndex && [1, 2].includes(tiles[i].layers[0].mode));
      only = only.filter((i) => !resolve.includes(i));
    }
    lastKey = key;
    const t0 = performance.now();
    renderer.drawValues(tiles, S.radiusScale, only);
    for (const i of resolve) renderer.resolveTile(tiles[i], liveShown[changed].tex, tiles[i].layers[0].mode);
    // Which tiles' index regions hold the points of their one layer, drawn whole.
    if (indexKey.length !== tiles.length) indexKey = tiles.map(() => null);
    tiles.forEach((t, i) => {
      if (only && !only.includes(i)) return;
      const l = t.layers.length === 1 ? t.layers[0] : null;
      if (!l || !l.keepIndex) indexKey[i] = l ? key : null;
      else if (!only) indexKey[i] = null;
    });
    view.resolved = resolve.length;
    // view.profile (set by a benchmark): the phases' times, each waited for.
    if (view.profile) { renderer.finish(); view.phases = { splat: performance.now() - t0, only }; }
    if (typeof S.exposure === 'number') {
      exposureStops = tiles.map(() => S.exposure);
    } else if (exposureDirty || !dragging || exposureStops.length !== tiles.length) {
      const groups = S.exposure === 'tile' ? tiles.map((_, i) => [i]) : [tiles.map((_, i) => i)];
      exposureStops = renderer.autoExposure(tiles, groups).stops;
      exposureDirty = false;
    }
    if (view.profile) { view.phases.exposure = performance.now() - t0 - view.phases.splat; }
    renderer.showValues(tiles, exposureStops, S.falseColour, S.background);
    if (view.profile) { renderer.finish(); view.phases.total = performance.now() - t0; }
    view.renders++;
    view.exposure = exposureStops[0] || 0;
    view.drawMs = performance.now() - t0;
    drawLabels(sheet);
    updateViewText(sheet);
    writeHash();
  }
  let scheduled = false;
  view.render = render;
  function scheduleRender() {
    if (scheduled) return;
    scheduled = true;
    requestAnimationFrame(() => { scheduled = false; render(); });
  }
  function drawLabels(sheet) {
    const box = $('labels');
    box.textContent = '';
    for (const t of sheet) {
      const div = document.createElement('div');
      div.className = 'label';
      div.style.left = t.x + 'px';
      div.style.top = t.y + 'px';
      for (const m of t.members) {
        const line = document.createElement('div');
        line.textContent = tileLabel(m) + (m.kind === 'live' && liveShown[m.input] && liveShown[m.input].stride > 1 ? ` (preview: 1 point in ${liveShown[m.input].stride})` : '');
        div.appendChild(line);
      }
      box.appendChild(div);
    }
  }
  // The batch ptview command of the same picture, when there is one.
  function batchCommand(sheet) {
    const shown = S.tiles.filter((t) => t.visible);
    if (shown.some((t) => t.kind === 'brick')) return 'brick-map voxels: no ptview equivalent (brickinfo -picture draws levels)';
    if (S.layout === 'overlay' && shown.length > 1) return 'overlaid clouds: no ptview equivalent';
    if (S.zoom !== 1 || S.panX !== 0 || S.panY !== 0) return 'zoomed or panned: no ptview equivalent (double-click resets)';
    const files = [], channels = [];
    for (const t of shown) {
      const f = t.kind === 'live' ? liveFileName(t.input) : inputOf(t.input).label;
      if (!files.includes(f)) files.push(f);
      const c = t.channel + (t.lum ? ':lum' : '');
      if (!channels.includes(c)) channels.push(c);
    }
    const cam = sheet[0].camera, words = ['ptview', '-res', cam.width, cam.height];
    if (cameraKind() === 'file') words.push('-camera', 'file');
    else words.push('-orbit', fmtExact(S.az), fmtExact(S.el), '-up', 'xyz'[S.up], '-fov', fmtExact(S.fov));
    words.push('-channel', channels.join(','));
    if (typeof S.exposure === 'number') words.push('-exposure', fmtExact(S.exposure));
    else if (S.exposure === 'tile') words.push('-exposure', 'tile');
    words.push('-falsecolor', S.falseColour ? 1 : 0);
    if (S.radiusScale !== 1) words.push('-radiusscale', fmtExact(S.radiusScale));
    words.push('-background', ...S.background.map(fmtExact));
    return words.concat(files.map(quote), ['view.png']).join(' ');
  }
  const fmtExact = (x) => String(x);
  const quote = (w) => (/^[A-Za-z0-9_./,:=+@%#-]+$/.test(w) ? w : `'${w.replace(/'/g, "'\\''")}'`);
  function updateViewText(sheet) {
    view.batchCommand = batchCommand(sheet);
    showCommand($('batch-command'), view.batchCommand);
    const e = typeof S.exposure === 'number' ? S.exposure : exposureStops[0] || 0;
    $('exposure-value').textContent = `${fmt(e)} stops${typeof S.exposure === 'number' ? '' : ' (auto)'}`;
    if (typeof S.exposure !== 'number') $('exposure').value = e;
  }

  // --- the live diffusion -----------------------------------------------------------
  const liveShown = {}; // input -> {buf, stride, points, hash, command, ...}
  let inFlight = null, pending = null;
  function presetOf(name) { return S.scene.materials.find((m) => m.name === name); }
  function liveFileName(input) {
    return S.live && S.live.cloud === input && S.live.name ? joinFolder(inputOf(input).save_folder, S.live.name) : '(save the live result first)';
  }
  const joinFolder = (folder, name) => (folder === '.' ? name : folder.replace(/\/$/, '') + '/' + name);
  function effectiveDmfp() { return S.live.dmfp.map((d) => d * Math.pow(2, S.live.scale)); }
  // ptfilter's option words of the material shown: what the server parses
  // and what the command line shows.
  function liveWords() {
    const L = S.live, p = presetOf(L.preset), words = ['-material', L.preset];
    const albedo = L.albedo.map(fmt), dmfp = effectiveDmfp().map(fmt);
    const same = albedo.every((a, i) => a === fmt(p.albedo[i])) && dmfp.every((d, i) => d === fmt(p.dmfp[i]));
    if (!same) words.push('-albedo', ...albedo, '-diffusemeanfreepath', ...dmfp);
    if (L.unitlength !== 1) words.push('-unitlength', fmt(L.unitlength));
    if (L.profile !== 'classic') words.push('-profile', L.profile);
    if (L.volume) words.push('-volume', '1');
    return words;
  }
  function requestLive(preview) {
    // Nothing to compute while no tile shows the live diffusion.
    if (!S.live || !S.tiles.some((t) => t.kind === 'live' && t.visible && t.input === S.live.cloud)) return;
    const req = { seq: ++view.liveSeq, preview, words: liveWords(), cloud: S.live.cloud, name: S.live.name, t0: performance.now() };
    if (preview && inFlight) { pending = req; return; }
    if (!preview) pending = null;
    send(req);
  }
  async function send(req) {
    inFlight = req;
    view.busy++;
    $('live-status').textContent = req.preview ? 'computing a preview…' : 'computing the whole cloud…';
    try {
      const url = `/api/diffuse?cloud=${req.cloud}&preview=${req.preview ? 1 : 0}&name=${encodeURIComponent(req.name)}`;
      const { meta, floats } = await fetchFloats(url, { method: 'POST', body: req.words.join('\n') });
      const tFetched = performance.now();
      if (meta.cancelled || req.seq < view.shownLiveSeq) return;
      const hash = hashFloats(floats);
      if (hash !== meta.hash) throw new Error(`live values damaged on the way (hash ${hash}, sent ${meta.hash})`);
      const old = liveShown[req.cloud];
      if (old) { renderer.release(old.buf); renderer.releaseTexture(old.tex); }
      liveShown[req.cloud] = { buf: renderer.buffer(floats), stride: meta.stride, points: meta.points, hash, command: meta.command, words: req.words,
                               tex: meta.stride === 1 ? renderer.valueTexture(floats, 3, meta.points) : null };
      view.shownLiveSeq = req.seq;
      exposureDirty = true;
      render(req.cloud);
      renderer.finish();
      const ms = performance.now() - req.t0;
      view.shownHash = hash;
      view.latencies.push({ seq: req.seq, preview: meta.stride > 1, ms, server: meta.seconds * 1000, points: meta.points,
                            answered: tFetched - req.t0, drawn: performance.now() - tFetched, resolved: view.resolved > 0 });
      showCommand($('command'), meta.command);
      $('live-status').textContent = `${meta.stride > 1 ? `preview, 1 point in ${meta.stride}` : 'whole cloud'}: ` +
        `${meta.points} points, diffusion ${(meta.seconds * 1000).toFixed(0)} ms, shown after ${ms.toFixed(0)} ms` +
        (meta.warnings.length ? ' — ' + meta.warnings.join('; ') : '');
      $('live-status').className = '';
      $('material-lines').textContent = meta.material.join('\n');
    } catch (e) {
      $('live-status').textContent = e.message;
      $('live-status').className = 'error';
    } finally {
      view.busy--;
      if (inFlight === req) inFlight = null;
      if (pending && !inFlight) { const p = pending; pending = null; send(p); }
    }
  }

  async function save() {
    const L = S.live;
    $('save-status').className = '';
    $('save-status').textContent = 'saving…';
    try {
      const url = `/api/save?cloud=${L.cloud}&name=${encodeURIComponent(L.name)}&overwrite=${$('overwrite').checked ? 1 : 0}`;
      const r = await (await fetchOk(url, { method: 'POST', body: liveWords().join('\n') })).json();
      $('save-status').textContent = `saved ${r.path} (values ${r.hash})`;
      view.saved = r;
      scheduleRender();
    } catch (e) {
      $('save-status').textContent = e.message;
      $('save-status').className = 'error';
    }
  }
  async function copyCommand() {
    const text = $('command').textContent;
    try {
      await navigator.clipboard.writeText(text);
      $('copy-status').textContent = 'copied';
    } catch (e) {
      const range = document.createRange();
      range.selectNodeContents($('command'));
      getSelection().removeAllRanges();
      getSelection().addRange(range);
      $('copy-status').textContent = document.execCommand && document.execCommand('copy') ? 'copied' : 'selected: copy it with Ctrl-C';
    }
  }

  async function turntable() {
    const shown = S.tiles.filter((t) => t.visible);
    const lines = shown.map((t) => `${t.kind === 'live' ? 'l' + t.input : sourceId(t)} ${t.channel}${t.lum ? ':lum' : ''}`);
    const { sheet } = layout();
    const q = new URLSearchParams({
      name: $('tt-name').value, frames: $('tt-frames').value, azimuth: S.az, elevation: S.el,
      up: S.up, fov: S.fov, width: sheet[0].camera.width, height: sheet[0].camera.height,
      exposure: typeof S.exposure === 'number' ? S.exposure : 'auto', falsecolor: S.falseColour ? 1 : 0,
      radiusscale: S.radiusScale, video: $('tt-video').value, overwrite: $('tt-overwrite').checked ? 1 : 0,
    });
    $('tt-status').className = '';
    $('tt-status').textContent = 'drawing the frames…';
    view.busy++;
    try {
      const r = await (await fetchOk('/api/turntable?' + q, { method: 'POST', body: lines.join('\n') })).json();
      view.turntable = r;
      $('tt-status').textContent = `${r.frames.length} frames in ${r.folder}` + (r.video ? `, video ${r.video}` : ` (${r.video_note})`);
    } catch (e) {
      $('tt-status').textContent = e.message;
      $('tt-status').className = 'error';
    } finally { view.busy--; }
  }

  // --- controls --------------------------------------------------------------------
  function option(select, value, text) {
    const o = document.createElement('option');
    o.value = value;
    o.textContent = text;
    select.appendChild(o);
    return o;
  }
  function sourceList() {
    const box = $('source-list');
    box.textContent = '';
    S.tiles.forEach((tile) => {
      const row = document.createElement('div');
      row.className = 'source';
      const show = document.createElement('input');
      show.type = 'checkbox';
      show.checked = tile.visible;
      show.title = 'show';
      show.addEventListener('change', async () => {
        tile.visible = show.checked;
        await refresh();
        if (tile.kind === 'live' && tile.visible && !liveShown[tile.input]) requestLive(false);
      });
      const name = document.createElement('span');
      name.textContent = inputOf(tile.input).label + (tile.kind === 'live' ? ' (live)' : '');
      name.title = name.textContent;
      const channel = document.createElement('select');
      for (const c of channelsOf(tile)) {
        option(channel, c.name, c.name);
        if (c.type !== 'float') option(channel, c.name + ':lum', c.name + ' (luminance)');
      }
      option(channel, 'N', 'N (normals)');
      option(channel, 'radius', 'radius');
      channel.value = tile.channel + (tile.lum ? ':lum' : '');
      channel.addEventListener('change', async () => {
        tile.lum = channel.value.endsWith(':lum');
        tile.channel = channel.value.replace(/:lum$/, '');
        exposureDirty = true;
        await refresh();
      });
      row.append(show, name, channel);
      if (tile.kind === 'brick') {
        const depth = document.createElement('select');
        for (const l of inputOf(tile.input).levels) option(depth, l.depth, `depth ${l.depth}: ${l.samples}`);
        depth.title = 'the depth whose voxels are drawn: samples';
        depth.value = tile.depth;
        depth.addEventListener('change', async () => { tile.depth = +depth.value; exposureDirty = true; await refresh(); });
        row.append(depth);
      }
      box.appendChild(row);
    });
  }
  async function refresh() {
    try {
      await Promise.all(S.tiles.filter((t) => t.visible).map(loadTile));
    } catch (e) { fail(e.message); }
    exposureDirty = true;
    render();
  }
  function rgbControls(id, values, min, max, log, onInput) {
    const box = $(id);
    box.textContent = '';
    ['R', 'G', 'B'].forEach((label, c) => {
      const row = document.createElement('label');
      const slider = document.createElement('input');
      slider.type = 'range'; slider.min = min; slider.max = max; slider.step = 0.001;
      slider.id = `${id}-${label.toLowerCase()}`;
      const number = document.createElement('input');
      number.type = 'number'; number.step = 'any';
      const show = () => { slider.value = log ? Math.log10(values()[c]) : values()[c]; number.value = fmt(values()[c]); };
      slider.addEventListener('input', () => { onInput(c, log ? Math.pow(10, +slider.value) : +slider.value); show(); requestLive(true); });
      slider.addEventListener('change', () => requestLive(false));
      number.addEventListener('change', () => { const v = +number.value; if (Number.isFinite(v) && v > 0) { onInput(c, v); show(); requestLive(false); } });
      row.append(label + ' ', slider, number);
      row.show = show;
      box.appendChild(row);
      show();
    });
  }
  function materialControls() {
    const L = S.live;
    rgbControls('albedo', () => L.albedo, 0, 0.999, false, (c, v) => { L.albedo[c] = Math.min(v, 0.999); });
    rgbControls('dmfp', effectiveDmfp, -2, 2, true, (c, v) => { L.dmfp[c] = v / Math.pow(2, L.scale); });
  }
  function setupLive() {
    const cloud = S.scene.inputs.find((i) => i.live);
    if (!cloud) { $('material').hidden = true; return; }
    $('material').hidden = false;
    const p = presetOf('marble');
    S.live = { cloud: cloud.index, preset: 'marble', albedo: p.albedo.slice(), dmfp: p.dmfp.slice(), scale: 0,
               unitlength: 1, profile: 'classic', volume: false,
               name: cloud.label.replace(/^.*\//, '').replace(/\.[^.]*$/, '').replace(/[^A-Za-z0-9_.+@-]/g, '_').replace(/^[.-]+/, '') + '_ssd.ptc' };
    for (const i of S.scene.inputs) if (i.live) option($('live-cloud'), i.index, i.label);
    for (const m of S.scene.materials) option($('preset'), m.name, m.name);
    for (const pr of S.scene.profiles) option($('profile'), pr, pr);
    $('preset').value = 'marble';
    $('save-name').value = S.live.name;
    $('live-cloud').addEventListener('change', () => { S.live.cloud = +$('live-cloud').value; requestLive(false); });
    $('preset').addEventListener('change', () => {
      const m = presetOf($('preset').value);
      Object.assign(S.live, { preset: m.name, albedo: m.albedo.slice(), dmfp: m.dmfp.slice(), scale: 0 });
      $('mfp-scale').value = 0;
      materialControls();
      requestLive(false);
    });
    $('mfp-scale').addEventListener('input', () => { S.live.scale = +$('mfp-scale').value; materialControls(); requestLive(true); });
    $('mfp-scale').addEventListener('change', () => requestLive(false));
    $('unitlength').value = 1;
    $('unitlength').addEventListener('change', () => { const v = +$('unitlength').value; if (v > 0) { S.live.unitlength = v; requestLive(false); } });
    $('profile').addEventListener('change', () => { S.live.profile = $('profile').value; requestLive(false); });
    $('volume').addEventListener('change', () => { S.live.volume = $('volume').checked; requestLive(false); });
    $('save-name').addEventListener('change', () => { S.live.name = $('save-name').value; requestLive(false); });
    $('save').addEventListener('click', save);
    $('copy').addEventListener('click', copyCommand);
    materialControls();
  }
  function viewControls() {
    const hasCamera = S.scene.inputs.some((i) => i.camera);
    $('camera').value = cameraKind();
    $('camera').querySelector('option[value=file]').disabled = !hasCamera;
    $('camera').addEventListener('change', () => { S.camera = $('camera').value; exposureDirty = true; render(); });
    $('layout').value = S.layout;
    $('layout').addEventListener('change', () => { S.layout = $('layout').value; exposureDirty = true; render(); });
    $('up').value = 'xyz'[S.up];
    $('up').addEventListener('change', () => { S.up = 'xyz'.indexOf($('up').value); exposureDirty = true; render(); });
    $('fov').value = S.fov;
    $('fov').addEventListener('change', () => { const v = +$('fov').value; if (v > 0 && v < 170) { S.fov = v; exposureDirty = true; render(); } });
    const res = $('res');
    if (S.res !== 'fit') option(res, S.res.join('x'), S.res.join(' x '));
    res.value = S.res === 'fit' ? 'fit' : S.res.join('x');
    res.addEventListener('change', () => { S.res = res.value === 'fit' ? 'fit' : res.value.split('x').map(Number); exposureDirty = true; render(); });
    $('exposure-mode').value = typeof S.exposure === 'number' ? 'fixed' : S.exposure;
    $('exposure-mode').addEventListener('change', () => {
      const m = $('exposure-mode').value;
      S.exposure = m === 'fixed' ? view.exposure : m;
      exposureDirty = true;
      render('display');
    });
    $('exposure').addEventListener('input', () => { S.exposure = +$('exposure').value; $('exposure-mode').value = 'fixed'; render('display'); });
    $('falsecolor').checked = S.falseColour;
    $('falsecolor').addEventListener('change', () => { S.falseColour = $('falsecolor').checked; render('display'); });
    $('radiusscale').value = Math.log2(S.radiusScale);
    $('radiusscale').addEventListener('input', () => { S.radiusScale = Math.pow(2, +$('radiusscale').value); exposureDirty = true; render(); });
    $('voxel-shape').value = S.voxelShape;
    $('voxel-shape').addEventListener('change', () => { S.voxelShape = $('voxel-shape').value; render(); });
    $('voxel-row').hidden = !S.scene.inputs.some((i) => i.kind === 'brickmap');
    $('reset-view').addEventListener('click', resetView);
    $('turntable-go').addEventListener('click', turntable);
    if (!S.scene.video.length) { $('tt-video').value = 'none'; $('tt-video').disabled = true; }
    window.addEventListener('resize', () => { if (S.res === 'fit') { exposureDirty = true; scheduleRender(); } });
  }
  function resetView() {
    Object.assign(S, { zoom: 1, panX: 0, panY: 0 });
    exposureDirty = true;
    render();
  }
  // Orbit with the left button, pan with the right one (or shift), zoom with
  // the wheel; a double click resets zoom and pan.
  function pointerControls() {
    const canvas = $('canvas');
    let last = null;
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('pointerdown', (e) => {
      last = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
      dragging = true;
      canvas.setPointerCapture(e.pointerId);
      if (cameraKind() === 'file') { S.camera = 'orbit'; $('camera').value = 'orbit'; }
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!last) return;
      const dx = e.clientX - last.x, dy = e.clientY - last.y;
      last.x = e.clientX; last.y = e.clientY;
      if (last.pan) {
        const h = renderer.height || 1;
        S.panX -= (2 * dx) / h / S.zoom; S.panY += (2 * dy) / h / S.zoom;
      } else {
        S.az = Math.round((S.az - dx * 0.4) * 100) / 100;
        S.el = Math.max(-90, Math.min(90, Math.round((S.el + dy * 0.4) * 100) / 100));
      }
      scheduleRender();
    });
    const end = () => { if (!last) return; last = null; dragging = false; exposureDirty = true; scheduleRender(); };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      S.zoom = Math.max(0.05, Math.min(200, S.zoom * Math.exp(-e.deltaY * 0.001)));
      exposureDirty = true;
      scheduleRender();
    }, { passive: false });
    canvas.addEventListener('dblclick', resetView);
  }

  // --- start -------------------------------------------------------------------------
  async function start() {
    try {
      renderer = new SssGl.Renderer($('canvas'));
      S.scene = await (await fetchOk('/api/scene')).json();
      const hash = readHash();
      S.tiles = initialTiles(hash);
      document.title = 'ptview · ' + S.scene.inputs.map((i) => i.label).join(', ');
      $('version').textContent = S.scene.software;
      viewControls();
      setupLive();
      sourceList();
      pointerControls();
      await refresh();
      if (S.live) requestLive(false);
      view.ready = true;
      setStatus(S.scene.inputs.map((i) => `${i.label}: ${i.kind === 'cloud' ? i.points + ' points' : 'brick map, ' + i.levels.length + ' depths'}`).join('; '));
    } catch (e) { fail(e.message); }
  }
  start();
})();
