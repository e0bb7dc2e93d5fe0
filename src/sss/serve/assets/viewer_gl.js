// ptview -serve: cameras and the WebGL2 splat renderer.
// The cameras are ptview's own (src/sss/view/point_view.cpp, ported in double
// precision), and every point is drawn as ptview draws it: a disc of its
// radius facing its normal, projected with the camera's Jacobian at its
// centre as an ellipse widened by 0.5 pixel^2, the nearest disc's plane
// winning per pixel (lower index on ties), one value per pixel, exposure and
// false colour after. So the page and `ptview` make the same picture of the
// same view, up to single-precision rounding on the GPU.
'use strict';

const SssGl = (() => {
  // --- 4x4 matrices, column-major like GLSL and glm: m[c * 4 + r] ----------
  const identity = () => { const m = new Float64Array(16); m[0] = m[5] = m[10] = m[15] = 1; return m; };
  function mul(a, b) {
    const m = new Float64Array(16);
    for (let c = 0; c < 4; ++c)
      for (let r = 0; r < 4; ++r) {
        let s = 0;
        for (let k = 0; k < 4; ++k) s += a[k * 4 + r] * b[c * 4 + k];
        m[c * 4 + r] = s;
      }
    return m;
  }
  function apply(m, p) {
    const out = [0, 0, 0, 0];
    for (let r = 0; r < 4; ++r) out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    return out;
  }
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const len = (a) => Math.sqrt(dot(a, a));
  const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const normalize = (a) => scale(a, 1 / len(a));

  // The camera a cloud was baked with: its world2ndc with the NDC square
  // fitted into width x height with the frame's aspect, centred.
  function fileAspect(format) {
    const x = format[0], y = format[1], pixel = format[2] > 0 ? format[2] : 1;
    return x > 0 && y > 0 ? (x * pixel) / y : 1;
  }
  function fileCamera(cam, width, height) {
    const aspect = fileAspect(cam.format);
    let fw = width, fh = height;
    if (width / height > aspect) fw = fh * aspect; else fh = fw / aspect;
    const ndc = identity();
    ndc[0] = fw; ndc[5] = fh; ndc[12] = 0.5 * (width - fw); ndc[13] = 0.5 * (height - fh);
    return { eye: Float64Array.from(cam.world2eye), raster: mul(ndc, Float64Array.from(cam.world2ndc)),
             width, height, minW: 0 };
  }

  // ptview's orbit camera (orbit_camera()); zoom and pan move it closer and
  // sideways (zoom 1, pan 0: exactly ptview -orbit AZ EL).
  function orbitCamera(bounds, az, el, upAxis, fov, width, height, zoom = 1, panX = 0, panY = 0) {
    const lo = bounds.slice(0, 3), hi = bounds.slice(3, 6);
    const centre = scale(add(lo, hi), 0.5);
    let radius = 0.5 * len(sub(hi, lo));
    if (!(radius > 0)) radius = 1;
    const up = [0, 0, 0];
    up[upAxis] = 1;
    let e1, e2;
    if (upAxis === 2) { e1 = [1, 0, 0]; e2 = [0, -1, 0]; }
    else if (upAxis === 1) { e1 = [1, 0, 0]; e2 = [0, 0, 1]; }
    else { e1 = [0, 1, 0]; e2 = [0, 0, 1]; }
    const a = (az * Math.PI) / 180, e = (el * Math.PI) / 180;
    const dir = add(scale(add(scale(e1, Math.sin(a)), scale(e2, Math.cos(a))), Math.cos(e)), scale(up, Math.sin(e)));
    const half = (0.5 * fov * Math.PI) / 180;
    const forward = scale(dir, -1);
    let right = cross(forward, up);
    if (len(right) < 1e-9) right = cross(forward, Math.sin(e) > 0 ? scale(e2, -1) : e2);
    right = normalize(right);
    const camUp = cross(right, forward);
    const tanHalf = Math.tan(half), short = Math.min(width, height);
    const fitX = (0.95 * tanHalf * width) / short, fitY = (0.95 * tanHalf * height) / short;
    const fits = (d) => {
      for (let k = 0; k < 8; ++k) {
        const corner = [k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]];
        const v = sub(corner, add(centre, scale(dir, d)));
        const z = dot(v, forward);
        if (!(z > 0) || Math.abs(dot(v, right)) > fitX * z || Math.abs(dot(v, camUp)) > fitY * z) return false;
      }
      return true;
    };
    let far = radius / Math.sin(half) / 0.95, near = 0;
    for (let it = 0; it < 60; ++it) {
      const mid = 0.5 * (near + far);
      if (fits(mid)) far = mid; else near = mid;
    }
    const distance = far;
    const shift = add(scale(right, panX * distance * tanHalf), scale(camUp, panY * distance * tanHalf));
    const eyePos = add(add(centre, shift), scale(dir, distance / zoom));
    const w2e = identity();
    for (let j = 0; j < 3; ++j) { w2e[j * 4] = right[j]; w2e[j * 4 + 1] = camUp[j]; w2e[j * 4 + 2] = forward[j]; }
    w2e[12] = -dot(right, eyePos); w2e[13] = -dot(camUp, eyePos); w2e[14] = -dot(forward, eyePos);
    const f = (0.5 * short) / tanHalf;
    const proj = new Float64Array(16);
    proj[0] = f; proj[8] = 0.5 * width; proj[5] = -f; proj[9] = 0.5 * height; proj[10] = 1; proj[11] = 1;
    return { eye: w2e, raster: mul(proj, w2e), width, height, minW: 1e-6 * (distance / zoom) };
  }

  // Eye-space depths of a box, for the depth buffer's range.
  function depthRange(cam, bounds) {
    let lo = Infinity, hi = 0;
    for (let k = 0; k < 8; ++k) {
      const z = apply(cam.eye, [k & 1 ? bounds[3] : bounds[0], k & 2 ? bounds[4] : bounds[1], k & 4 ? bounds[5] : bounds[2]])[2];
      lo = Math.min(lo, z); hi = Math.max(hi, z);
    }
    const span = Math.max(hi - lo, 1e-6 * Math.max(Math.abs(hi), 1));
    return [lo - span, 1 / (3 * span)];
  }

  // --- shaders ----------------------------------------------------------------
  const SPLAT_VS = `#version 300 es
precision highp float;
layout(location = 0) in vec3 a_p;
layout(location = 1) in vec3 a_n;
layout(location = 2) in float a_r;
layout(location = 3) in vec3 a_v;
uniform mat4 u_raster, u_eye;
uniform vec2 u_size;
uniform float u_minw, u_rscale, u_maxsize;
uniform int u_mode, u_square;
flat out vec3 v_value;
flat out float v_kind;
flat out vec2 v_centre;
flat out vec3 v_conic;
flat out vec4 v_plane; // depth, d(depth)/dx, d(depth)/dy, max |change|
flat out vec2 v_extent;
flat out uint v_index;
void cull() { gl_Position = vec4(2.0, 2.0, 2.0, 1.0); }
void main() {
  vec4 h = u_raster * vec4(a_p, 1.0);
  float depth = (u_eye * vec4(a_p, 1.0)).z;
  if (!(h.w > u_minw) || !(depth > 0.0)) { cull(); return; }
  vec2 c = h.xy / h.w;
  vec3 jx, jy;
  for (int j = 0; j < 3; ++j) {
    jx[j] = (u_raster[j][0] - c.x * u_raster[j][3]) / h.w;
    jy[j] = (u_raster[j][1] - c.y * u_raster[j][3]) / h.w;
  }
  float r = a_r * u_rscale;
  vec3 gz = vec3(u_eye[0][2], u_eye[1][2], u_eye[2][2]);
  float sxx, sxy, syy, gx = 0.0, gy = 0.0;
  float nl = length(a_n);
  if (nl > 0.0 && u_square == 0) {
    vec3 n = a_n / nl;
    float sgn = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + n.z), b = n.x * n.y * a;
    vec3 t1 = vec3(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    vec3 t2 = vec3(b, sgn + n.y * n.y * a, -n.y);
    vec2 a1 = vec2(dot(jx, t1), dot(jy, t1)), a2 = vec2(dot(jx, t2), dot(jy, t2));
    sxx = r * r * (a1.x * a1.x + a2.x * a2.x);
    sxy = r * r * (a1.x * a1.y + a2.x * a2.y);
    syy = r * r * (a1.y * a1.y + a2.y * a2.y);
    float det = a1.x * a2.y - a2.x * a1.y;
    if (abs(det) * r * r > 0.01) {
      float b1 = dot(gz, t1), b2 = dot(gz, t2);
      gx = (b1 * a2.y - b2 * a1.y) / det;
      gy = (b2 * a1.x - b1 * a2.x) / det;
    }
  } else {
    sxx = r * r * dot(jx, jx); sxy = r * r * dot(jx, jy); syy = r * r * dot(jy, jy);
  }
  sxx += 0.5; syy += 0.5;
  float dets = sxx * syy - sxy * sxy;
  if (!(dets > 0.0)) { cull(); return; }
  vec2 ext = vec2(sqrt(sxx), sqrt(syy));
  // A point sprite over the ellipse's box (the fragment test cuts it): it
  // covers the pixels whose centres are within size / 2 of the centre.
  gl_PointSize = min(2.0 * max(ext.x, ext.y) + 0.5, u_maxsize);
  gl_Position = vec4(2.0 * c.x / u_size.x - 1.0, 1.0 - 2.0 * c.y / u_size.y, 0.0, 1.0);
  v_centre = c;
  v_conic = vec3(syy, -sxy, sxx) / dets;
  v_plane = vec4(depth, gx, gy, r * length(gz));
  v_extent = ext;
  vec3 v = a_v;
  float kind = 1.0;
  if (u_mode == 0) v = vec3(a_v.x);
  else if (u_mode == 1) kind = 2.0;
  else if (u_mode == 2) v = vec3(dot(a_v, vec3(0.2126, 0.7152, 0.0722)));
  else if (u_mode == 3) { float l = length(a_v); v = l > 0.0 ? a_v / l : vec3(0.0); kind = 3.0; }
  else if (u_mode == 4) { v = nl > 0.0 ? a_n / nl : vec3(0.0); kind = 3.0; }
  else v = vec3(a_r);
  v_value = v;
  v_kind = kind;
  v_index = uint(gl_VertexID) + 1u;
}`;
  const SPLAT_FS = `#version 300 es
precision highp float;
precision highp int;
uniform vec2 u_origin, u_size;
uniform vec2 u_depth; // eye depth at 0, 1 / span
uniform int u_square;
flat in vec3 v_value;
flat in float v_kind;
flat in vec2 v_centre;
flat in vec3 v_conic;
flat in vec4 v_plane;
flat in vec2 v_extent;
flat in uint v_index;
layout(location = 0) out vec4 o_value;
layout(location = 1) out uint o_index;
void main() {
  vec2 pr = vec2(gl_FragCoord.x - u_origin.x, u_origin.y + u_size.y - gl_FragCoord.y);
  vec2 d = pr - v_centre;
  if (u_square == 1) {
    if (abs(d.x) > v_extent.x || abs(d.y) > v_extent.y) discard;
  } else if (v_conic.x * d.x * d.x + 2.0 * v_conic.y * d.x * d.y + v_conic.z * d.y * d.y > 1.0) {
    discard;
  }
  float dz = clamp(v_plane.y * d.x + v_plane.z * d.y, -v_plane.w, v_plane.w);
  gl_FragDepth = clamp((v_plane.x + dz - u_depth.x) * u_depth.y, 0.0, 1.0);
  o_value = vec4(v_value, v_kind);
  o_index = v_index;
}`;
  // A tile's values again from the point drawn at each pixel (the index
  // target) and new per-point values: what a new live result needs when the
  // view has not changed, without drawing a point.
  const RESOLVE_FS = `#version 300 es
precision highp float;
precision highp int;
uniform highp usampler2D u_index;
uniform highp sampler2D u_values;
uniform int u_mode, u_width;
out vec4 o_value;
void main() {
  uint i = texelFetch(u_index, ivec2(gl_FragCoord.xy), 0).r;
  if (i == 0u) { o_value = vec4(0.0); return; }
  int k = int(i - 1u);
  vec3 v = texelFetch(u_values, ivec2(k % u_width, k / u_width), 0).rgb;
  o_value = u_mode == 2 ? vec4(vec3(dot(v, vec3(0.2126, 0.7152, 0.0722))), 1.0) : vec4(v, 2.0);
}`;
  const SHOW_VS = `#version 300 es
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}`;
  // Exposure, false colour and the sRGB curve of ptview's PNG pictures.
  const SHOW_FS = `#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D u_values;
uniform float u_gain;
uniform int u_false;
uniform vec3 u_background;
out vec4 o_colour;
float srgb(float x) { return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055; }
void main() {
  vec4 t = texelFetch(u_values, ivec2(gl_FragCoord.xy), 0);
  vec3 c;
  if (t.a < 0.5) c = u_background;
  else if (t.a > 2.5) c = 0.5 + 0.5 * t.rgb;
  else {
    vec3 v = t.rgb * u_gain;
    if (u_false == 1) {
      float lum = t.a < 1.5 ? v.x : dot(v, vec3(0.2126, 0.7152, 0.0722));
      c = lum < 0.0 ? -lum * vec3(0.1, 0.3, 1.0) : max(v, vec3(0.0));
    } else c = v;
  }
  c = clamp(c, 0.0, 1.0);
  o_colour = vec4(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);
}`;

  function compile(gl, vs, fs) {
    const program = gl.createProgram();
    for (const [type, text] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, text);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
      gl.attachShader(program, s);
    }
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(program));
    const uniforms = {};
    const n = gl.getProgramParameter(program, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; ++i) {
      const name = gl.getActiveUniform(program, i).name;
      uniforms[name] = gl.getUniformLocation(program, name);
    }
    return { program, uniforms };
  }

  // The kth smallest of a Float32Array's first n values (nth_element).
  function select(a, n, k) {
    let lo = 0, hi = n - 1;
    while (hi > lo) {
      const pivot = a[(lo + hi) >> 1];
      let i = lo, j = hi;
      while (i <= j) {
        while (a[i] < pivot) ++i;
        while (a[j] > pivot) --j;
        if (i <= j) { const t = a[i]; a[i] = a[j]; a[j] = t; ++i; --j; }
      }
      if (k <= j) hi = j; else if (k >= i) lo = i; else break;
    }
    return a[k];
  }

  class Renderer {
    constructor(canvas) {
      const gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: false,
                                               preserveDrawingBuffer: true });
      if (!gl) throw new Error('this browser has no WebGL2');
      this.floatTarget = !!gl.getExtension('EXT_color_buffer_float');
      if (!this.floatTarget) throw new Error('this browser cannot render to float textures (EXT_color_buffer_float)');
      this.gl = gl;
      this.canvas = canvas;
      this.splat = compile(gl, SPLAT_VS, SPLAT_FS);
      this.show = compile(gl, SHOW_VS, SHOW_FS);
      this.resolve = compile(gl, SHOW_VS, RESOLVE_FS);
      this.vao = gl.createVertexArray();
      this.maxPointSize = gl.getParameter(gl.ALIASED_POINT_SIZE_RANGE)[1];
      this.width = this.height = 0;
    }

    resize(width, height) {
      const gl = this.gl;
      if (width === this.width && height === this.height) return;
      this.canvas.width = width; this.canvas.height = height;
      this.canvas.style.width = width + 'px'; this.canvas.style.height = height + 'px';
      this.width = width; this.height = height;
      if (this.fbo) {
        gl.deleteFramebuffer(this.fbo); gl.deleteFramebuffer(this.valuesFbo);
        gl.deleteTexture(this.values); gl.deleteTexture(this.index); gl.deleteRenderbuffer(this.depth);
      }
      const texture = (format) => {
        const t = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, t);
        gl.texStorage2D(gl.TEXTURE_2D, 1, format, width, height);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
        return t;
      };
      this.values = texture(gl.RGBA32F); // value, kind (0: no point)
      this.index = texture(gl.R32UI);    // the point drawn + 1 (0: none)
      this.depth = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, this.depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT32F, width, height);
      this.fbo = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.fbo);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.values, 0);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT1, gl.TEXTURE_2D, this.index, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, this.depth);
      if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) throw new Error('cannot render to a float texture');
      this.valuesFbo = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.valuesFbo);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.values, 0);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    }

    // Per-point values as a texture (RGB, `width` texels a row), for resolve().
    valueTexture(floats, comps, n) {
      const gl = this.gl, width = 4096, rows = Math.max(1, Math.ceil(n / width));
      const data = new Float32Array(width * rows * 3);
      if (comps === 3) data.set(floats.subarray(0, 3 * n));
      else for (let i = 0; i < n; ++i) data[3 * i] = data[3 * i + 1] = data[3 * i + 2] = floats[i];
      const t = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB32F, width, rows, 0, gl.RGB, gl.FLOAT, data);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      return { texture: t, width };
    }
    releaseTexture(t) { if (t) this.gl.deleteTexture(t.texture); }

    // Writes a tile's values from its index region and per-point values (a
    // valueTexture()); mode 1 colour, 2 luminance.
    resolveTile(t, values, mode) {
      const gl = this.gl, u = this.resolve.uniforms, cam = t.camera;
      const originY = this.height - t.y - cam.height;
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.valuesFbo);
      gl.viewport(t.x, originY, cam.width, cam.height);
      gl.useProgram(this.resolve.program);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, this.index);
      gl.activeTexture(gl.TEXTURE1);
      gl.bindTexture(gl.TEXTURE_2D, values.texture);
      gl.uniform1i(u.u_index, 0);
      gl.uniform1i(u.u_values, 1);
      gl.uniform1i(u.u_mode, mode);
      gl.uniform1i(u.u_width, values.width);
      gl.bindVertexArray(this.vao);
      for (let i = 0; i < 4; ++i) gl.disableVertexAttribArray(i);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      gl.bindVertexArray(null);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    }

    buffer(data) {
      const gl = this.gl, b = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, b);
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
      return b;
    }
    release(b) { if (b) this.gl.deleteBuffer(b); }

    // Draws the tiles' values into the float target. Each tile: {x, y (from
    // the top), camera, layers: [{n, pos, nrm, rad, val, comps, mode, square}],
    // depth: [near, 1 / span]}. `only`: the indices of the tiles to draw again
    // (the others keep their values); all when null.
    drawValues(tiles, radiusScale, only = null) {
      const gl = this.gl, u = this.splat.uniforms;
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.fbo);
      gl.viewport(0, 0, this.width, this.height);
      gl.disable(gl.SCISSOR_TEST);
      gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
      if (!only) {
        gl.clearBufferfv(gl.COLOR, 0, [0, 0, 0, 0]);
        gl.clearBufferuiv(gl.COLOR, 1, [0, 0, 0, 0]);
        gl.clearBufferfv(gl.DEPTH, 0, [1]);
      }
      gl.enable(gl.DEPTH_TEST);
      gl.enable(gl.SCISSOR_TEST);
      gl.depthFunc(gl.LESS);
      gl.useProgram(this.splat.program);
      gl.uniform1f(u.u_maxsize, this.maxPointSize);
      gl.bindVertexArray(this.vao);
      tiles.forEach((t, index) => {
        if (only && !only.includes(index)) return;
        const cam = t.camera, originY = this.height - t.y - cam.height;
        gl.viewport(t.x, originY, cam.width, cam.height);
        gl.scissor(t.x, originY, cam.width, cam.height);
        if (only) {
          gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
          gl.clearBufferfv(gl.COLOR, 0, [0, 0, 0, 0]);
          // A subsample keeps the whole cloud's indices (for resolveTile()).
          if (!t.layers.some((l) => l.keepIndex)) gl.clearBufferuiv(gl.COLOR, 1, [0, 0, 0, 0]);
          gl.clearBufferfv(gl.DEPTH, 0, [1]);
        }
        gl.uniformMatrix4fv(u.u_raster, false, Float32Array.from(cam.raster));
        gl.uniformMatrix4fv(u.u_eye, false, Float32Array.from(cam.eye));
        gl.uniform2f(u.u_size, cam.width, cam.height);
        gl.uniform2f(u.u_origin, t.x, originY);
        gl.uniform2f(u.u_depth, t.depth[0], t.depth[1]);
        gl.uniform1f(u.u_minw, cam.minW);
        gl.uniform1f(u.u_rscale, radiusScale);
        for (const l of t.layers) {
          gl.drawBuffers([gl.COLOR_ATTACHMENT0, l.keepIndex ? gl.NONE : gl.COLOR_ATTACHMENT1]);
          gl.uniform1i(u.u_mode, l.mode);
          gl.uniform1i(u.u_square, l.square ? 1 : 0);
          const attribs = [[0, l.pos, 3], [1, l.nrm, 3], [2, l.rad, 1], [3, l.val || l.rad, l.val ? l.comps : 1]];
          for (const [loc, buf, size] of attribs) {
            gl.bindBuffer(gl.ARRAY_BUFFER, buf);
            gl.enableVertexAttribArray(loc);
            gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 0, 0);

          }
          gl.drawArrays(gl.POINTS, 0, l.n);
        }
      });
      gl.bindVertexArray(null);
      gl.drawBuffers([gl.COLOR_ATTACHMENT0]);
      gl.disable(gl.DEPTH_TEST);
      gl.disable(gl.SCISSOR_TEST);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    }

    // The automatic exposure of ptview: the 99.5th percentile of the largest
    // |component| of the covered pixels (normals left out) is shown as 1.
    // groups: lists of tiles that share one exposure. Returns stops per tile.
    autoExposure(tiles, groups) {
      const gl = this.gl;
      gl.bindFramebuffer(gl.FRAMEBUFFER, this.fbo);
      const pixels = new Float32Array(this.width * this.height * 4);
      gl.readPixels(0, 0, this.width, this.height, gl.RGBA, gl.FLOAT, pixels);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      const stops = new Array(tiles.length).fill(0);
      const refs = new Array(tiles.length).fill(0);
      for (const group of groups) {
        let count = 0;
        for (const i of group) count += tiles[i].camera.width * tiles[i].camera.height;
        const mags = new Float32Array(count);
        let n = 0;
        for (const i of group) {
          const t = tiles[i], y0 = this.height - t.y - t.camera.height;
          for (let y = y0; y < y0 + t.camera.height; ++y)
            for (let x = t.x; x < t.x + t.camera.width; ++x) {
              const k = 4 * (y * this.width + x), kind = pixels[k + 3];
              if (kind < 0.5 || kind > 2.5) continue;
              mags[n++] = Math.max(Math.abs(pixels[k]), Math.abs(pixels[k + 1]), Math.abs(pixels[k + 2]));
            }
        }
        let ref = 0;
        if (n > 0) ref = select(mags, n, Math.min(n - 1, Math.floor(0.995 * (n - 1) + 0.5)));
        for (const i of group) { refs[i] = ref; stops[i] = ref > 0 ? -Math.log2(ref) : 0; }
      }
      return { stops, refs };
    }

    // The picture: gap grey 0.2 between tiles, each tile exposed.
    showValues(tiles, stops, falseColour, background) {
      const gl = this.gl, u = this.show.uniforms;
      const gap = 124 / 255; // sRGB of 0.2, rounded as ptview's PNG
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.viewport(0, 0, this.width, this.height);
      gl.clearColor(gap, gap, gap, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.useProgram(this.show.program);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, this.values);
      gl.uniform1i(u.u_values, 0);
      gl.uniform1i(u.u_false, falseColour ? 1 : 0);
      gl.uniform3f(u.u_background, background[0], background[1], background[2]);
      gl.bindVertexArray(this.vao);
      for (let i = 0; i < 4; ++i) gl.disableVertexAttribArray(i);
      tiles.forEach((t, i) => {
        gl.viewport(t.x, this.height - t.y - t.camera.height, t.camera.width, t.camera.height);
        gl.uniform1f(u.u_gain, Math.pow(2, stops[i]));
        gl.drawArrays(gl.TRIANGLES, 0, 3);
      });
      gl.bindVertexArray(null);
    }

    // Waits for the GPU (a one-pixel read), so that a time measured after
    // it includes the drawing.
    finish() {
      const gl = this.gl, px = new Uint8Array(4);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    }
  }

  return { Renderer, orbitCamera, fileCamera, fileAspect, depthRange, mul, apply };
})();
