/* swarm replay viewer: decodes the .swr recording embedded in this page and draws it on a canvas.
 *
 * No libraries and nothing fetched: the recording is base64 in <script id="swr-data">, its chunks are
 * zlib streams inflated with the browser's DecompressionStream, their bodies msgpack (decoded below).
 * The format is docs/recording-format.md; the Python reader is swarm/record/reader.py.
 *
 * Version 2 recordings add the communication streams: failed deliveries with their cause, the tick's groups,
 * map merges (age of information) and contacts; version 1 files still play, without those layers.
 *
 * For tests and scripting, window.swarmViewer exposes setTick, select, pose, robotScreenPosition, and what
 * the last frame drew: drawnLosses(), drawnGroups(), aoi() ...
 */
(function () {
  'use strict';

  const MAGIC = [0x89, 0x53, 0x57, 0x52, 0x0d, 0x0a, 0x1a, 0x0a];
  const UNSEEN = 0, FREE = 1, SOLID = 2;
  const RSSI_NAN = -32768, RSSI_NEG_INF = -32767, RSSI_POS_INF = 32767;
  const FLASH_TICKS = 6;          // a message stays visible this many ticks, fading
  const LOST_TICKS = 6;           // so does a failed delivery
  const TRAIL_POINTS = 600;       // points per robot and trail (fading or limited trails are redrawn every frame)
  const TRAIL_BANDS = 10;         // a fading trail is drawn in this many bands of equal age, oldest faintest
  const READABLE_VERSIONS = [1, 2, 3];
  const CAUSE_STYLE = {           // colour and explanation of each failed-delivery cause (HEAD loss_causes)
    link: [[200, 0, 0], 'no link: the receiver is out of the radio\'s reach (or failed)'],
    loss: [[230, 0, 180], 'random packet loss (comm.loss)'],
    bandwidth: [[30, 30, 30], 'the link\'s byte budget for the tick was spent (comm.bandwidth)'],
    packet_error: [[255, 130, 0], 'a packet error on a link above the sensitivity (radio.per)'],
  };
  const KEYFRAME_BUDGET = 96e6;   // bytes of state snapshots kept for fast scrubbing

  // ------------------------------------------------------------------------------ decoding ----
  function base64ToBytes(text) {
    const bin = atob(text.replace(/\s+/g, ''));
    const out = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
    return out;
  }

  async function inflate(bytes) {
    if (typeof DecompressionStream === 'undefined') {
      throw new Error('this browser has no DecompressionStream; use a current Chromium, Firefox or Safari');
    }
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }

  function unpackMsgpack(u8) {
    const dv = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
    const text = new TextDecoder();
    let pos = 0;
    const str = (n) => { const s = text.decode(u8.subarray(pos, pos + n)); pos += n; return s; };
    const bin = (n) => { const b = u8.subarray(pos, pos + n); pos += n; return b; };
    const arr = (n) => { const a = new Array(n); for (let i = 0; i < n; i++) a[i] = read(); return a; };
    const map = (n) => { const o = {}; for (let i = 0; i < n; i++) { const k = read(); o[String(k)] = read(); } return o; };
    const u16 = () => { const v = dv.getUint16(pos); pos += 2; return v; };
    const u32 = () => { const v = dv.getUint32(pos); pos += 4; return v; };
    function read() {
      const b = u8[pos++];
      if (b <= 0x7f) return b;
      if (b >= 0xe0) return b - 256;
      if ((b & 0xf0) === 0x80) return map(b & 0x0f);
      if ((b & 0xf0) === 0x90) return arr(b & 0x0f);
      if ((b & 0xe0) === 0xa0) return str(b & 0x1f);
      let v;
      switch (b) {
        case 0xc0: return null;
        case 0xc2: return false;
        case 0xc3: return true;
        case 0xc4: return bin(u8[pos++]);
        case 0xc5: return bin(u16());
        case 0xc6: return bin(u32());
        case 0xc7: pos += 2 + u8[pos]; return null;           // ext: not used by the format, skipped
        case 0xc8: pos += 3 + dv.getUint16(pos); return null;
        case 0xc9: pos += 5 + dv.getUint32(pos); return null;
        case 0xca: v = dv.getFloat32(pos); pos += 4; return v;
        case 0xcb: v = dv.getFloat64(pos); pos += 8; return v;
        case 0xcc: return u8[pos++];
        case 0xcd: return u16();
        case 0xce: return u32();
        case 0xcf: v = Number(dv.getBigUint64(pos)); pos += 8; return v;
        case 0xd0: v = dv.getInt8(pos); pos += 1; return v;
        case 0xd1: v = dv.getInt16(pos); pos += 2; return v;
        case 0xd2: v = dv.getInt32(pos); pos += 4; return v;
        case 0xd3: v = Number(dv.getBigInt64(pos)); pos += 8; return v;
        case 0xd4: pos += 2; return null;
        case 0xd5: pos += 3; return null;
        case 0xd6: pos += 5; return null;
        case 0xd7: pos += 9; return null;
        case 0xd8: pos += 17; return null;
        case 0xd9: return str(u8[pos++]);
        case 0xda: return str(u16());
        case 0xdb: return str(u32());
        case 0xdc: return arr(u16());
        case 0xdd: return arr(u32());
        case 0xde: return map(u16());
        case 0xdf: return map(u32());
      }
      throw new Error('msgpack: unexpected byte 0x' + b.toString(16) + ' at ' + (pos - 1));
    }
    return read();
  }

  const DTYPES = { '<f8': [Float64Array, 8], '<u4': [Uint32Array, 4], '<u2': [Uint16Array, 2],
                   '<i2': [Int16Array, 2], '|u1': [Uint8Array, 1] };

  /** A [dtype, shuffled, bytes] triple as a typed array (copied: typed arrays need aligned buffers). */
  function typed(triple) {
    const [dtype, shuffled, raw] = triple;
    const [Ctor, size] = DTYPES[dtype];
    const n = raw.length / size;
    const out = new Uint8Array(raw.length);
    if (shuffled && size > 1) {
      for (let p = 0; p < size; p++) {
        const base = p * n;
        for (let i = 0; i < n; i++) out[i * size + p] = raw[base + i];
      }
    } else {
      out.set(raw);
    }
    return new Ctor(out.buffer);
  }

  function concat(parts, Ctor) {
    let n = 0;
    for (const p of parts) n += p.length;
    const out = new Ctor(n);
    let at = 0;
    for (const p of parts) { out.set(p, at); at += p.length; }
    return out;
  }

  function prefix(counts) {
    const out = new Float64Array(counts.length + 1);
    for (let i = 0; i < counts.length; i++) out[i + 1] = out[i] + counts[i];
    return out;
  }

  function ungap(gaps, off) {
    const out = new Uint32Array(gaps.length);
    for (let t = 0; t + 1 < off.length; t++) {
      let acc = 0;
      for (let k = off[t]; k < off[t + 1]; k++) { acc += gaps[k]; out[k] = acc; }
    }
    return out;
  }

  async function parseRecording(bytes) {
    for (let i = 0; i < MAGIC.length; i++) {
      if (bytes[i] !== MAGIC[i]) throw new Error('not a .swr recording');
    }
    const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    const chunks = [];
    let pos = MAGIC.length;
    while (pos + 12 <= bytes.length) {
      const kind = String.fromCharCode(bytes[pos], bytes[pos + 1], bytes[pos + 2], bytes[pos + 3]);
      const length = dv.getUint32(pos + 4, true);
      const payload = bytes.subarray(pos + 12, pos + 12 + length);
      if (payload.length !== length) throw new Error('truncated recording');
      chunks.push([kind, unpackMsgpack(await inflate(payload))]);
      pos += 12 + length;
    }
    if (!chunks.length || chunks[0][0] !== 'HEAD' || chunks[chunks.length - 1][0] !== 'TAIL') {
      throw new Error('incomplete recording');
    }
    const head = chunks[0][1];
    const tail = chunks[chunks.length - 1][1];
    if (!READABLE_VERSIONS.includes(head.version)) {
      throw new Error(`format version ${head.version}; this viewer knows ${READABLE_VERSIONS.join(', ')}`);
    }
    const hasComm = head.version >= 2;
    // version 3: link, RSSI and merge indices stored as per-tick gaps; msg_rssi as differences from the RSSI
    // stream (not drawn: the viewer shows the stream's values)
    const gapped = head.version >= 3;
    const blocks = chunks.slice(1, -1).map((c) => c[1]);
    if (gapped) {
      for (const b of blocks) { b.link_idx = b.link_gap; b.rssi_idx = b.rssi_gap; b.aoi_idx = b.aoi_gap; }
    }
    const commStreams = ['group', 'aoi', 'contact'];
    const streams = ['known', 'seen', 'link', 'rssi', 'msg', 'act', ...(hasComm ? commStreams : [])];
    const commArrays = ['msg_via', 'msg_lost_n', 'msg_lost', 'msg_lost_cause', 'group_robot', 'group_id', 'aoi_idx',
                        'aoi_val', 'contact_robot', 'team_free'];
    const arrays = ['pose', 'metrics', 'known_gap', 'known_val', 'seen_gap', 'link_idx', 'rssi_idx', 'rssi_val',
                    'msg_sender', 'msg_seq', 'msg_type', 'msg_size', 'msg_recv_n', 'msg_recv', 'msg_rssi',
                    'act_robot', ...streams.map((s) => s + '_n'), ...(hasComm ? commArrays : [])];
    const parts = {};
    for (const name of arrays) parts[name] = [];
    const typeNames = [], typeCode = {}, msgTypeParts = [], acts = [];
    for (const b of blocks) {
      for (const name of arrays) parts[name].push(typed(b[name]));
      const local = b.msg_types.map((name) => {
        if (!(name in typeCode)) { typeCode[name] = typeNames.length; typeNames.push(name); }
        return typeCode[name];
      });
      const codes = parts.msg_type[parts.msg_type.length - 1];
      msgTypeParts.push(Uint16Array.from(codes, (c) => local[c]));
      for (const a of b.act) acts.push(a);
    }
    const cat = {};
    for (const name of arrays) cat[name] = concat(parts[name], parts[name].length ? parts[name][0].constructor : Uint8Array);
    const R = head.n_robots, H = head.shape[0], W = head.shape[1];
    const T = tail.ticks;
    if (!hasComm) {   // version 1: no communication streams; every message is its sender's own
      const none = new Uint16Array(0), zeros = new Uint32Array(T);
      Object.assign(cat, { msg_via: cat.msg_sender, msg_lost_n: new Uint16Array(cat.msg_sender.length),
                           msg_lost: none, msg_lost_cause: new Uint8Array(0), group_robot: none, group_id: none,
                           aoi_idx: new Uint32Array(0), aoi_val: new Uint32Array(0), contact_robot: none,
                           team_free: zeros });
      for (const s of commStreams) cat[s + '_n'] = zeros;
    }
    const off = {};
    for (const s of [...streams, ...(hasComm ? [] : commStreams)]) off[s] = prefix(cat[s + '_n']);
    const explored = new Float64Array(T), coverage = new Float64Array(T);
    for (let t = 0; t < T; t++) { explored[t] = cat.metrics[2 * t]; coverage[t] = cat.metrics[2 * t + 1]; }
    const msgTick = new Uint32Array(cat.msg_sender.length);
    for (let t = 0; t < T; t++) for (let k = off.msg[t]; k < off.msg[t + 1]; k++) msgTick[k] = t;
    const actTick = new Uint32Array(acts.length);
    for (let t = 0; t < T; t++) for (let k = off.act[t]; k < off.act[t + 1]; k++) actTick[k] = t;
    return {
      head, tail, R, H, W, T, off, explored, coverage, hasComm,
      poses: cat.pose, material: typed(head.material),
      knownIdx: ungap(cat.known_gap, off.known), knownVal: cat.known_val,
      seenIdx: ungap(cat.seen_gap, off.seen), linkIdx: gapped ? ungap(cat.link_idx, off.link) : cat.link_idx,
      rssiIdx: gapped ? ungap(cat.rssi_idx, off.rssi) : cat.rssi_idx, rssiVal: cat.rssi_val,
      msg: { sender: cat.msg_sender, seq: cat.msg_seq, type: concat(msgTypeParts, Uint16Array), size: cat.msg_size,
             recvOff: prefix(cat.msg_recv_n), recv: cat.msg_recv, rssi: cat.msg_rssi, tick: msgTick, types: typeNames,
             via: cat.msg_via, lostOff: prefix(cat.msg_lost_n), lost: cat.msg_lost, lostCause: cat.msg_lost_cause },
      causes: head.loss_causes || [],
      group: { robot: cat.group_robot, id: cat.group_id },
      aoi: { idx: gapped ? ungap(cat.aoi_idx, off.aoi) : cat.aoi_idx, val: cat.aoi_val },
      contact: { robot: cat.contact_robot },
      teamFree: cat.team_free,
      act: { robot: cat.act_robot, data: acts, tick: actTick, decoded: new Map() },
    };
  }

  // ------------------------------------------------------------------------------ state ----
  /** Knowledge maps, union seen raster, links and RSSI at one tick, with keyframes for fast seeking. */
  class ReplayState {
    constructor(rec) {
      this.rec = rec;
      const { R, H, W, T } = rec;
      this.known = new Uint8Array(R * H * W);
      this.seen = new Uint8Array(H * W);
      this.link = new Uint8Array(R * R);
      this.rssi = new Int16Array(R * R).fill(RSSI_NAN);
      this.counts = new Float64Array(3 * R);   // per robot: cells UNSEEN, FREE, SOLID
      for (let i = 0; i < R; i++) this.counts[3 * i] = H * W;
      this.groupOf = new Int32Array(R).fill(-1);       // per robot: its group's smallest member
      this.mergedAt = new Float64Array(R * R);         // [i * R + s]: when i last merged (a map holding) s's map
      this.lastContact = new Float64Array(R).fill(-1); // per robot: the last tick it received a message
      this.cells = H * W;
      this.tick = -1;
      const snapshotBytes = R * H * W + H * W + 11 * R * R;
      const count = Math.max(1, Math.floor(KEYFRAME_BUDGET / snapshotBytes));
      this.every = Math.max(32, Math.ceil(T / count));
      this.keyframes = [];
      for (let t = 0; t < T; t++) {
        if (t % this.every === 0) this.keyframes.push(this.snapshot());
        this.apply(t);
      }
    }

    snapshot() {
      return { tick: this.tick, known: this.known.slice(), seen: this.seen.slice(), link: this.link.slice(),
               rssi: this.rssi.slice(), counts: this.counts.slice(), groupOf: this.groupOf.slice(),
               mergedAt: this.mergedAt.slice(), lastContact: this.lastContact.slice() };
    }

    restore(k) {
      this.known.set(k.known); this.seen.set(k.seen); this.link.set(k.link); this.rssi.set(k.rssi);
      this.counts.set(k.counts); this.groupOf.set(k.groupOf); this.mergedAt.set(k.mergedAt);
      this.lastContact.set(k.lastContact);
      this.tick = k.tick;
    }

    apply(t) {
      const r = this.rec, off = r.off;
      const known = this.known, counts = this.counts, cells = this.cells;
      for (let k = off.known[t]; k < off.known[t + 1]; k++) {
        const idx = r.knownIdx[k], base = 3 * Math.floor(idx / cells);
        counts[base + known[idx]]--;
        counts[base + r.knownVal[k]]++;
        known[idx] = r.knownVal[k];
      }
      for (let k = off.seen[t]; k < off.seen[t + 1]; k++) this.seen[r.seenIdx[k]] = 1;
      for (let k = off.link[t]; k < off.link[t + 1]; k++) this.link[r.linkIdx[k]] ^= 1;
      for (let k = off.rssi[t]; k < off.rssi[t + 1]; k++) this.rssi[r.rssiIdx[k]] = r.rssiVal[k];
      for (let k = off.group[t]; k < off.group[t + 1]; k++) this.groupOf[r.group.robot[k]] = r.group.id[k];
      for (let k = off.aoi[t]; k < off.aoi[t + 1]; k++) this.mergedAt[r.aoi.idx[k]] = r.aoi.val[k];
      for (let k = off.contact[t]; k < off.contact[t + 1]; k++) this.lastContact[r.contact.robot[k]] = t;
      this.tick = t;
    }

    seek(t) {
      if (t === this.tick) return;
      if (t < this.tick || t - this.tick > this.every) {
        this.restore(this.keyframes[Math.floor(t / this.every)]);
      }
      for (let s = this.tick + 1; s <= t; s++) this.apply(s);
    }
  }

  // ------------------------------------------------------------------------------ drawing helpers ----
  const RAMP = [[0, [215, 48, 39]], [10, [252, 141, 89]], [20, [254, 224, 139]], [30, [145, 207, 96]], [40, [26, 152, 80]]];

  function rampColour(margin) {
    if (!(margin > RAMP[0][0])) return RAMP[0][1];
    for (let i = 1; i < RAMP.length; i++) {
      if (margin <= RAMP[i][0]) {
        const [a, ca] = RAMP[i - 1], [b, cb] = RAMP[i];
        const f = (margin - a) / (b - a);
        return ca.map((c, k) => Math.round(c + f * (cb[k] - c)));
      }
    }
    return RAMP[RAMP.length - 1][1];
  }

  const rgb = (c, a = 1) => `rgba(${c[0]},${c[1]},${c[2]},${a})`;
  const mix = (a, b, f) => a.map((v, k) => Math.round(v + f * (b[k] - v)));

  function typeColour(name) {
    if (name === 'swarm.map_update') return [40, 110, 220];
    if (name === 'swarm.map_request') return [120, 60, 200];
    let h = 0;
    for (let i = 0; i < name.length; i++) h = (h * 31 + name.charCodeAt(i)) >>> 0;
    return [40 + h % 160, 40 + (h >> 8) % 160, 40 + (h >> 16) % 160];
  }

  function isPoint(v) {
    return Array.isArray(v) && v.length >= 2 && v.length <= 6 && typeof v[0] === 'number' && typeof v[1] === 'number'
      && isFinite(v[0]) && isFinite(v[1]);
  }

  function fmt(v, digits = 2) { return typeof v === 'number' ? v.toFixed(digits) : String(v); }

  function escapeHtml(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  }

  function plural(n, word) { return `${n} ${word}${n === 1 ? '' : 's'}`; }

  function causeColour(cause) { return (CAUSE_STYLE[cause] || [[90, 90, 90]])[0]; }
  function causeText(cause) { return (CAUSE_STYLE[cause] || [null, cause])[1]; }

  /** Convex hull of [x, y] points (Andrew's monotone chain), counter-clockwise; 1 or 2 points as given. */
  function convexHull(points) {
    const p = points.slice().sort((a, b) => a[0] - b[0] || a[1] - b[1]);
    if (p.length < 3) return p;
    const cross = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    const lower = [], upper = [];
    for (const q of p) {
      while (lower.length >= 2 && cross(lower[lower.length - 2], lower[lower.length - 1], q) <= 0) lower.pop();
      lower.push(q);
    }
    for (let i = p.length - 1; i >= 0; i--) {
      const q = p[i];
      while (upper.length >= 2 && cross(upper[upper.length - 2], upper[upper.length - 1], q) <= 0) upper.pop();
      upper.push(q);
    }
    return lower.slice(0, -1).concat(upper.slice(0, -1));
  }

  function segmentDistance(px, py, x1, y1, x2, y2) {
    const dx = x2 - x1, dy = y2 - y1, len = dx * dx + dy * dy;
    const f = len ? Math.max(0, Math.min(1, ((px - x1) * dx + (py - y1) * dy) / len)) : 0;
    return Math.hypot(px - x1 - f * dx, py - y1 - f * dy);
  }

  // ------------------------------------------------------------------------------ viewer ----
  class Viewer {
    constructor(rec, cfg) {
      this.rec = rec;
      this.cfg = cfg;
      this.state = new ReplayState(rec);
      this.head = rec.head;
      this.cellM = rec.head.cell_m;
      this.quantum = rec.head.rssi_quantum_db;
      this.sens = rec.head.sensitivity_dbm;
      this.colours = rec.head.colours;
      this.robotColours = cfg.robotColours;
      this.tick = 0;
      this.selectedRobot = null;
      this.playing = false;
      this.canvas = document.getElementById('map');
      this.ctx = this.canvas.getContext('2d');
      this.curve = document.getElementById('curve');
      this.slider = document.getElementById('timeline');
      this.base = document.createElement('canvas');
      this.base.width = rec.W; this.base.height = rec.H;
      this.baseCtx = this.base.getContext('2d');
      this.image = this.baseCtx.createImageData(rec.W, rec.H);
      this.baseKey = '';
      this.actIndex = this.indexActions();
      this.messageTotals = this.cumulativeMessages();
      this.trails = document.createElement('canvas');
      this.trailTick = -1;
      this.trailRange = [0, 0];
      this.groupLayer = document.createElement('canvas');
      this.drawn = { losses: [], groups: [] };
      this.tip = document.getElementById('tooltip');
      this.trailSeconds = document.getElementById('trail-seconds');
      this.trailFade = document.getElementById('trail-fade');
      this.hiddenCauses = new Set();
      this.layout();
      this.bind();
      this.renderLegend();
      this.setTick(0);
    }

    colour(i) { return this.robotColours[i % this.robotColours.length]; }

    indexActions() {
      const per = Array.from({ length: this.rec.R }, () => []);
      const a = this.rec.act;
      for (let k = 0; k < a.robot.length; k++) per[a.robot[k]].push(k);
      return per;
    }

    /** Per tick and robot, running totals of messages sent, bytes sent and messages received (so the
     *  robot panel is O(1) per frame during playback). */
    cumulativeMessages() {
      const { R, T, msg, off } = this.rec;
      const sent = new Float64Array(T * R), bytes = new Float64Array(T * R), received = new Float64Array(T * R);
      const s = new Float64Array(R), b = new Float64Array(R), r = new Float64Array(R);
      for (let t = 0; t < T; t++) {
        for (let k = off.msg[t]; k < off.msg[t + 1]; k++) {
          s[msg.via[k]]++; b[msg.via[k]] += msg.size[k];   // the transmitter (a relay sends copies)
          for (let q = msg.recvOff[k]; q < msg.recvOff[k + 1]; q++) r[msg.recv[q]]++;
        }
        sent.set(s, t * R); bytes.set(b, t * R); received.set(r, t * R);
      }
      return { sent, bytes, received };
    }

    action(k) {
      const a = this.rec.act;
      if (!a.decoded.has(k)) {
        const f = unpackMsgpack(a.data[k]);
        a.decoded.set(k, f === null ? null : { goal: f[0], velocity: f[1], clear_goal: f[2], debug: f[3] });
      }
      return a.decoded.get(k);
    }

    /** Index into robot i's action list of its latest action at or before tick t (-1 if none). */
    latestAction(i, t) {
      const list = this.actIndex[i], ticks = this.rec.act.tick;
      let lo = 0, hi = list.length - 1, best = -1;
      while (lo <= hi) {
        const mid = (lo + hi) >> 1;
        if (ticks[list[mid]] <= t) { best = mid; lo = mid + 1; } else hi = mid - 1;
      }
      return best;
    }

    currentGoal(i, t) {
      const list = this.actIndex[i];
      for (let j = this.latestAction(i, t), seen = 0; j >= 0 && seen < 5000; j--, seen++) {
        const act = this.action(list[j]);
        if (act === null) return null;
        if (isPoint(act.goal)) return act.goal;
        if (act.clear_goal) return null;
      }
      return null;
    }

    // -------------------------------------------------------------------------- geometry ----
    layout() {
      const { W, H } = this.rec;
      const aside = 380, pad = 40;
      const maxW = Math.max(200, window.innerWidth - aside - pad);
      const maxH = Math.max(200, window.innerHeight - 80);
      this.cellPx = Math.max(0.5, Math.min(maxW / W, maxH / H));
      this.canvas.width = Math.max(1, Math.round(W * this.cellPx));
      this.canvas.height = Math.max(1, Math.round(H * this.cellPx));
      this.cellPx = this.canvas.width / W;
      this.canvas.style.width = this.canvas.width + 'px';
      this.canvas.style.height = this.canvas.height + 'px';
      this.robotPx = Math.max(4, this.head.robot_radius_m / this.cellM * this.cellPx);
    }

    worldToCanvas(x, y) {
      return [x / this.cellM * this.cellPx, (this.rec.H - y / this.cellM) * this.cellPx];
    }

    pose(i, t = this.tick) {
      const p = this.rec.poses, k = (t * this.rec.R + i) * 3;
      return [p[k], p[k + 1], p[k + 2]];
    }

    robotScreenPosition(i) {
      const [x, y] = this.pose(i);
      const [cx, cy] = this.worldToCanvas(x, y);
      const rect = this.canvas.getBoundingClientRect();
      return { x: rect.left + cx, y: rect.top + cy, canvasX: cx, canvasY: cy, radius: this.robotPx };
    }

    // -------------------------------------------------------------------------- ui ----
    bind() {
      const s = this.slider;
      s.max = String(this.rec.T - 1);
      s.addEventListener('input', () => this.setTick(Number(s.value)));
      document.getElementById('play').addEventListener('click', () => (this.playing ? this.pause() : this.play()));
      this.speed = document.getElementById('speed');
      for (const id of ['show-links', 'show-messages', 'show-trails', 'show-debug', 'show-groups', 'show-lost',
                        'trail-fade']) {
        document.getElementById(id).addEventListener('change', () => this.draw());
      }
      this.trailSeconds.addEventListener('input', () => this.draw());
      this.canvas.addEventListener('mousemove', (e) => {
        const rect = this.canvas.getBoundingClientRect();
        this.showTip(e.clientX - rect.left, e.clientY - rect.top, e.clientX, e.clientY);
      });
      this.canvas.addEventListener('mouseleave', () => { this.tip.hidden = true; });
      this.canvas.addEventListener('click', (e) => {
        const rect = this.canvas.getBoundingClientRect();
        this.select(this.robotAt(e.clientX - rect.left, e.clientY - rect.top));
      });
      document.getElementById('robot-close').addEventListener('click', () => this.select(null));
      document.addEventListener('keydown', (e) => {
        if (e.target && (e.target.tagName === 'SELECT' || e.target.type === 'number')) return;
        if (e.key === ' ') { e.preventDefault(); this.playing ? this.pause() : this.play(); }
        if (e.target === this.slider) return;
        const step = e.shiftKey ? 10 : 1;
        if (e.key === 'ArrowRight') this.setTick(this.tick + step);
        if (e.key === 'ArrowLeft') this.setTick(this.tick - step);
      });
      window.addEventListener('resize', () => { this.layout(); this.baseKey = ''; this.trailTick = -1; this.draw(); });
    }

    robotAt(cx, cy) {
      let best = null, bestD = Math.max(this.robotPx + 4, 8);
      for (let i = 0; i < this.rec.R; i++) {
        const [x, y] = this.pose(i);
        const [px, py] = this.worldToCanvas(x, y);
        const d = Math.hypot(px - cx, py - cy);
        if (d <= bestD) { best = i; bestD = d; }
      }
      return best;
    }

    setTick(t) {
      t = Math.max(0, Math.min(this.rec.T - 1, Math.round(Number(t)) || 0));
      this.tick = t;
      this.state.seek(t);
      this.slider.value = String(t);
      this.draw();
    }

    play() {
      if (this.tick >= this.rec.T - 1) this.setTick(0);
      this.playing = true;
      const button = document.getElementById('play');
      button.dataset.playing = '1';
      button.innerHTML = '&#10074;&#10074; Pause';
      let last = performance.now(), carry = 0;
      const step = (now) => {
        if (!this.playing) return;
        carry += (now - last) / 1000 * 10 * Number(this.speed.value);
        last = now;
        const n = Math.floor(carry);
        if (n > 0) { carry -= n; this.setTick(this.tick + n); }
        if (this.tick >= this.rec.T - 1) { this.pause(); return; }
        requestAnimationFrame(step);
      };
      requestAnimationFrame(step);
    }

    pause() {
      this.playing = false;
      const button = document.getElementById('play');
      button.dataset.playing = '0';
      button.innerHTML = '&#9654; Play';
    }

    select(i) {
      this.selectedRobot = (i === null || i === undefined) ? null : Number(i);
      const panel = document.getElementById('robot-panel');
      panel.hidden = this.selectedRobot === null;
      panel.dataset.robot = this.selectedRobot === null ? '' : String(this.selectedRobot);
      this.draw();
    }

    // -------------------------------------------------------------------------- drawing ----
    draw() {
      this.drawBase();
      const ctx = this.ctx;
      ctx.imageSmoothingEnabled = false;
      ctx.drawImage(this.base, 0, 0, this.canvas.width, this.canvas.height);
      this.drawn = { losses: [], groups: [] };
      if (this.rec.hasComm && document.getElementById('show-groups').checked) this.drawGroups();
      if (document.getElementById('show-trails').checked) this.drawTrails();
      if (document.getElementById('show-links').checked) this.drawLinks();
      if (document.getElementById('show-messages').checked) this.drawMessages();
      if (document.getElementById('show-lost').checked) this.drawLosses();
      if (this.selectedRobot !== null && document.getElementById('show-debug').checked) this.drawDebug(this.selectedRobot);
      this.drawRobots();
      this.drawCurve();
      this.updateReadout();
      this.updateAoi();
      if (this.selectedRobot !== null) this.updatePanel(this.selectedRobot);
    }

    drawBase() {
      const key = this.tick + ':' + this.selectedRobot + ':' + this.canvas.width;
      if (key === this.baseKey) return;
      this.baseKey = key;
      const { W, H } = this.rec;
      const data = this.image.data, mat = this.rec.material, seen = this.state.seen;
      const unseenFree = this.cfg.unseenFree, seenFree = this.cfg.seenFree, othersFree = this.cfg.othersFree;
      const faded = this.colours.map((c) => mix(c, unseenFree, 0.55));
      const half = this.colours.map((c) => mix(c, othersFree, 0.35));
      const r = this.selectedRobot;
      const known = this.state.known, base = r === null ? 0 : r * W * H;
      for (let row = 0; row < H; row++) {
        const out = (H - 1 - row) * W;
        for (let col = 0; col < W; col++) {
          const cell = row * W + col, m = mat[cell];
          let c;
          if (r === null) {
            c = m ? (seen[cell] ? this.colours[m] : faded[m]) : (seen[cell] ? seenFree : unseenFree);
          } else {
            const k = known[base + cell];
            if (k === SOLID) c = m ? this.colours[m] : this.colours[1] || [60, 60, 60];
            else if (k === FREE) c = seenFree;
            else if (seen[cell]) c = m ? half[m] : othersFree;
            else c = m ? faded[m] : unseenFree;
          }
          const p = (out + col) * 4;
          data[p] = c[0]; data[p + 1] = c[1]; data[p + 2] = c[2]; data[p + 3] = 255;
        }
      }
      this.baseCtx.putImageData(this.image, 0, 0);
    }

    /** Trails: the whole run's path, or the last N seconds of it (``trail-seconds``), fading with age
     *  (``trail-fade``): a faded or limited trail is redrawn every frame from at most TRAIL_POINTS points per
     *  robot, in TRAIL_BANDS bands of equal age, the oldest faintest. */
    drawTrails() {
      const seconds = Math.max(0, Number(this.trailSeconds.value) || 0);
      const fade = this.trailFade.checked;
      if (!fade && !seconds) { this.drawWholeTrails(); return; }
      const t = this.tick, ctx = this.ctx;
      const from = seconds ? Math.max(0, t - Math.round(seconds / this.head.tick_s)) : 0;
      this.trailRange = [from, t];
      const span = t - from;
      if (span < 1) return;
      const stride = Math.max(1, Math.ceil(span / TRAIL_POINTS));
      const bands = fade ? Math.min(TRAIL_BANDS, span) : 1;
      ctx.save();
      ctx.lineWidth = 1.5; ctx.lineJoin = 'round'; ctx.lineCap = 'butt';
      for (let i = 0; i < this.rec.R; i++) {
        const colour = mix(this.colour(i), [255, 255, 255], 0.35);
        for (let b = 0; b < bands; b++) {
          const a = from + Math.floor(b * span / bands), z = from + Math.floor((b + 1) * span / bands);
          ctx.strokeStyle = rgb(colour, fade ? 0.08 + 0.92 * (b + 1) / bands : 1);
          ctx.beginPath();
          ctx.moveTo(...this.worldToCanvas(...this.pose(i, a)));
          for (let s = (Math.floor(a / stride) + 1) * stride; s < z; s += stride) {
            ctx.lineTo(...this.worldToCanvas(...this.pose(i, s)));
          }
          ctx.lineTo(...this.worldToCanvas(...this.pose(i, z)));
          ctx.stroke();
        }
      }
      ctx.restore();
    }

    /** The whole run's trails, unfaded, live on their own canvas, extended incrementally as time moves
     *  forward (a full redraw of 16 long trails costs ~50 ms in software rendering; a few new segments cost
     *  nothing). */
    drawWholeTrails() {
      const t = this.tick, layer = this.trails;
      this.trailRange = [0, t];
      if (layer.width !== this.canvas.width || layer.height !== this.canvas.height || t < this.trailTick) {
        layer.width = this.canvas.width; layer.height = this.canvas.height;
        this.trailTick = -1;
      }
      if (t > this.trailTick) {
        const ctx = layer.getContext('2d');
        const from = Math.max(0, this.trailTick);
        const stride = Math.max(1, Math.floor((t - from) / 1500));
        ctx.lineWidth = 1.5;
        ctx.lineJoin = 'round';
        ctx.lineCap = 'round';
        for (let i = 0; i < this.rec.R; i++) {
          ctx.strokeStyle = rgb(mix(this.colour(i), [255, 255, 255], 0.35));
          ctx.beginPath();
          let [x, y] = this.worldToCanvas(...this.pose(i, from));
          ctx.moveTo(x, y);
          for (let s = from + stride; s < t; s += stride) {
            [x, y] = this.worldToCanvas(...this.pose(i, s));
            ctx.lineTo(x, y);
          }
          [x, y] = this.worldToCanvas(...this.pose(i, t));
          ctx.lineTo(x, y);
          ctx.stroke();
        }
        this.trailTick = t;
      }
      this.ctx.drawImage(layer, 0, 0);
    }

    /** Communication groups (as radio.LinkState.groups(): strongly connected over the tick's links) of two
     *  or more robots: the convex hull of their positions, widened by a robot, in the colour of the group's
     *  smallest member (so it stays put while the group keeps that member). */
    drawGroups() {
      const groups = this.groups().filter((g) => g.length > 1);
      if (!groups.length) return;
      const layer = this.groupLayer, pad = this.robotPx + 6;
      if (layer.width !== this.canvas.width || layer.height !== this.canvas.height) {
        layer.width = this.canvas.width; layer.height = this.canvas.height;
      }
      const g = layer.getContext('2d');
      g.clearRect(0, 0, layer.width, layer.height);
      g.lineJoin = 'round'; g.lineCap = 'round'; g.lineWidth = 2 * pad;
      let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
      for (const members of groups) {
        const hull = convexHull(members.map((i) => this.worldToCanvas(...this.pose(i))));
        const colour = this.colour(members[0]);
        g.fillStyle = g.strokeStyle = rgb(colour);
        g.beginPath();
        hull.forEach(([x, y], k) => (k ? g.lineTo(x, y) : g.moveTo(x, y)));
        g.closePath(); g.fill(); g.stroke();
        for (const [x, y] of hull) {
          x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y);
        }
        this.drawn.groups.push({ members, colour, hull });
      }
      // drawn opaque on their own layer, then blended once (overlapping strokes do not darken), only the
      // part the hulls cover: compositing the whole canvas costs milliseconds in software rendering
      x0 = Math.max(0, Math.floor(x0 - pad - 1)); y0 = Math.max(0, Math.floor(y0 - pad - 1));
      x1 = Math.min(layer.width, Math.ceil(x1 + pad + 1)); y1 = Math.min(layer.height, Math.ceil(y1 + pad + 1));
      if (x1 <= x0 || y1 <= y0) return;
      this.ctx.save(); this.ctx.globalAlpha = 0.3;
      this.ctx.drawImage(layer, x0, y0, x1 - x0, y1 - y0, x0, y0, x1 - x0, y1 - y0);
      this.ctx.restore();
    }

    /** Failed deliveries of the last LOST_TICKS ticks' transmissions, fading: a dashed line in the cause's
     *  colour from the transmitter three quarters of the way to the robot it did not reach, ending in a
     *  cross. With a robot selected, only those from or to it. One path per tick and cause (a stroke per
     *  line cost milliseconds a frame when 16 robots share maps out of reach). */
    drawLosses() {
      const ctx = this.ctx, m = this.rec.msg, off = this.rec.off.msg, causes = this.rec.causes;
      const sel = this.selectedRobot;
      ctx.save();
      ctx.lineWidth = 2;
      for (let t = Math.max(0, this.tick - LOST_TICKS + 1); t <= this.tick; t++) {
        const lines = new Map();
        for (let k = off[t]; k < off[t + 1]; k++) {
          if (m.lostOff[k] === m.lostOff[k + 1]) continue;
          const from = m.via[k];
          const [sx, sy] = this.worldToCanvas(...this.pose(from));
          for (let q = m.lostOff[k]; q < m.lostOff[k + 1]; q++) {
            const cause = causes[m.lostCause[q]], to = m.lost[q];
            if (this.hiddenCauses.has(cause) || (sel !== null && from !== sel && to !== sel)) continue;
            if (!lines.has(cause)) lines.set(cause, [new Path2D(), new Path2D()]);
            const [dashed, crosses] = lines.get(cause);
            const [rx, ry] = this.worldToCanvas(...this.pose(to));
            const ex = sx + 0.75 * (rx - sx), ey = sy + 0.75 * (ry - sy);
            dashed.moveTo(sx, sy); dashed.lineTo(ex, ey);
            crosses.moveTo(ex - 3.5, ey - 3.5); crosses.lineTo(ex + 3.5, ey + 3.5);
            crosses.moveTo(ex + 3.5, ey - 3.5); crosses.lineTo(ex - 3.5, ey + 3.5);
            this.drawn.losses.push({ tick: t, from, to, sender: m.sender[k], seq: m.seq[k], cause,
                                     type: m.types[m.type[k]], x1: sx, y1: sy, x2: ex, y2: ey,
                                     colour: causeColour(cause) });
          }
        }
        const alpha = 1 - (this.tick - t) / LOST_TICKS;
        for (const [cause, [dashed, crosses]] of lines) {
          ctx.strokeStyle = rgb(causeColour(cause), alpha);
          ctx.setLineDash([5, 4]); ctx.stroke(dashed);
          ctx.setLineDash([]); ctx.stroke(crosses);
        }
      }
      ctx.restore();
    }

    /** The tooltip for what is under the mouse: a failed delivery (the newest first), else a group. */
    showTip(cx, cy, pageX, pageY) {
      let text = '';
      let best = 6;
      for (const d of this.drawn.losses) {
        const dist = segmentDistance(cx, cy, d.x1, d.y1, d.x2, d.y2);
        if (dist <= best) {   // ties: the newest, drawn last, on top
          best = dist;
          const relay = d.from !== d.sender ? ` relayed by ${d.from}` : '';
          const margin = this.margin(d.to, d.from);
          const m = isFinite(margin) ? `; RSSI margin now ${fmt(margin, 1)} dB` : '';
          text = `Lost at tick ${d.tick} (${(d.tick * this.head.tick_s).toFixed(1)} s): robot ${d.sender} → ` +
                 `robot ${d.to}, ${d.type} #${d.seq}${relay}. Cause: ${d.cause}: ${causeText(d.cause)}${m}.`;
        }
      }
      if (!text) {
        const pad = this.robotPx + 6;
        for (const g of this.drawn.groups) {
          const h = g.hull;
          let near = false;
          for (let k = 0; k < h.length && !near; k++) {
            const [x1, y1] = h[k], [x2, y2] = h[(k + 1) % h.length];
            near = segmentDistance(cx, cy, x1, y1, x2, y2) <= pad;
          }
          if (near || (h.length > 2 && this.insidePolygon(cx, cy, h))) {
            text = `Communication group of ${g.members.length}: robots ${g.members.join(', ')}`;
          }
        }
      }
      this.tip.hidden = !text;
      if (text) {
        this.tip.textContent = text;
        this.tip.style.left = (pageX + 14 + window.scrollX) + 'px';
        this.tip.style.top = (pageY + 10 + window.scrollY) + 'px';
      }
    }

    insidePolygon(x, y, poly) {
      let inside = false;
      for (let i = 0, j = poly.length - 1; i < poly.length; j = i++) {
        const [xi, yi] = poly[i], [xj, yj] = poly[j];
        if ((yi > y) !== (yj > y) && x < (xj - xi) * (y - yi) / (yj - yi) + xi) inside = !inside;
      }
      return inside;
    }

    /** The tick's communication groups, each its members in order, sorted by smallest member (none in a
     *  version 1 recording). */
    groups() {
      if (!this.rec.hasComm) return [];
      const by = new Map(), of = this.state.groupOf;
      for (let i = 0; i < this.rec.R; i++) {
        if (!by.has(of[i])) by.set(of[i], []);
        by.get(of[i]).push(i);
      }
      return [...by.values()].sort((a, b) => a[0] - b[0]);
    }

    /** Per robot at this tick, as the run's metrics define them (docs/comm-metrics.md): its group (smallest
     *  member), age of information and time since contact (ticks) and the share of the team's known free
     *  cells its map lacks. */
    commState() {
      const R = this.rec.R, st = this.state, t = this.tick, team = this.rec.teamFree[t];
      const out = [];
      for (let i = 0; i < R; i++) {
        let age = 0, since = 0, missing = 0;
        if (R > 1) {  // a lone robot has no one to miss, wait for or hear
          let sum = 0;
          for (let s = 0; s < R; s++) if (s !== i) sum += st.mergedAt[i * R + s];
          age = t - sum / (R - 1);
          since = t - Math.max(st.lastContact[i], 0);
          if (team > 0) missing = Math.min(Math.max(1 - st.counts[3 * i + FREE] / team, 0), 1);
        }
        out.push({ robot: i, group: st.groupOf[i], age, since, missing });
      }
      return out;
    }

    /** The age-of-information panel: a row per robot, bars scaled to the largest age at this tick. */
    updateAoi() {
      const body = document.getElementById('aoi-rows');
      if (!this.rec.hasComm) return;
      const rows = this.commState(), tickS = this.head.tick_s;
      const sizes = new Map();
      for (const r of rows) sizes.set(r.group, (sizes.get(r.group) || 0) + 1);
      const scale = Math.max(10, ...rows.map((r) => r.age));
      if (body.children.length !== rows.length) {
        body.innerHTML = rows.map((r) => `<tr data-robot="${r.robot}"><td><span class="swatch" ` +
          `style="background:${rgb(this.colour(r.robot))}"></span>${r.robot}</td><td class="grp"></td>` +
          '<td class="num since"></td><td class="bar age"><span></span><em></em></td>' +
          '<td class="bar missing"><span></span><em></em></td></tr>').join('');
      }
      rows.forEach((r, i) => {
        const tr = body.children[i];
        tr.dataset.group = String(r.group); tr.dataset.age = String(r.age);
        tr.dataset.since = String(r.since); tr.dataset.missing = String(r.missing);
        const n = sizes.get(r.group);
        tr.querySelector('.grp').innerHTML = `<span class="swatch" style="background:${rgb(this.colour(r.group))}">` +
          `</span>${n > 1 ? 'with ' + (n - 1) : 'alone'}`;
        tr.querySelector('.since').textContent = (r.since * tickS).toFixed(1) + ' s';
        const age = tr.querySelector('.age'), missing = tr.querySelector('.missing');
        age.querySelector('span').style.width = (100 * r.age / scale).toFixed(1) + '%';
        age.querySelector('em').textContent = (r.age * tickS).toFixed(1) + ' s';
        missing.querySelector('span').style.width = (100 * r.missing).toFixed(1) + '%';
        missing.querySelector('em').textContent = (100 * r.missing).toFixed(0) + ' %';
      });
    }

    margin(receiver, sender) {
      const q = this.state.rssi[receiver * this.rec.R + sender];
      if (q === RSSI_NAN) return NaN;
      if (q === RSSI_NEG_INF) return -Infinity;
      if (q === RSSI_POS_INF) return Infinity;
      return q * this.quantum - this.sens[receiver];
    }

    drawLinks() {
      const ctx = this.ctx, R = this.rec.R, link = this.state.link;
      ctx.lineWidth = 2.5;
      for (let i = 0; i < R; i++) {
        const [xi, yi] = this.worldToCanvas(...this.pose(i));
        for (let j = i + 1; j < R; j++) {
          const ij = link[i * R + j], ji = link[j * R + i];
          if (!ij && !ji) continue;
          let m = Infinity;
          if (ij) m = Math.min(m, this.margin(i, j));
          if (ji) m = Math.min(m, this.margin(j, i));
          const [xj, yj] = this.worldToCanvas(...this.pose(j));
          ctx.strokeStyle = rgb(rampColour(isFinite(m) ? m : 40), 0.85);
          ctx.setLineDash(ij && ji ? [] : [6, 4]);
          ctx.beginPath(); ctx.moveTo(xi, yi); ctx.lineTo(xj, yj); ctx.stroke();
        }
      }
      ctx.setLineDash([]);
    }

    drawMessages() {
      const ctx = this.ctx, m = this.rec.msg, off = this.rec.off.msg;
      const first = Math.max(0, this.tick - FLASH_TICKS + 1);
      for (let k = off[first]; k < off[this.tick + 1]; k++) {
        const age = this.tick - m.tick[k];
        const alpha = 1 - age / FLASH_TICKS;
        const colour = typeColour(m.types[m.type[k]]);
        const [sx, sy] = this.worldToCanvas(...this.pose(m.via[k]));
        ctx.lineWidth = 2;
        ctx.strokeStyle = rgb(colour, 0.8 * alpha);
        for (let q = m.recvOff[k]; q < m.recvOff[k + 1]; q++) {
          const [rx, ry] = this.worldToCanvas(...this.pose(m.recv[q]));
          const f = Math.min(1, (age + 1) / 3);   // the flash travels from sender to receiver
          ctx.beginPath(); ctx.moveTo(sx, sy); ctx.lineTo(sx + f * (rx - sx), sy + f * (ry - sy)); ctx.stroke();
        }
        const delivered = m.recvOff[k + 1] > m.recvOff[k];
        ctx.strokeStyle = delivered ? rgb(colour, alpha) : rgb([120, 120, 120], alpha);
        ctx.beginPath(); ctx.arc(sx, sy, this.robotPx + 3 + 2 * age, 0, 2 * Math.PI); ctx.stroke();
      }
    }

    drawDebug(i) {
      const ctx = this.ctx, colour = this.colour(i);
      const wMax = this.rec.W * this.cellM, hMax = this.rec.H * this.cellM;
      const inside = (p) => p[0] >= 0 && p[1] >= 0 && p[0] <= wMax && p[1] <= hMax;
      const mark = (p, size, filled) => {
        const [x, y] = this.worldToCanvas(p[0], p[1]);
        ctx.beginPath(); ctx.rect(x - size, y - size, 2 * size, 2 * size);
        if (filled) ctx.fill(); ctx.stroke();
      };
      ctx.lineWidth = 1.5;
      ctx.strokeStyle = rgb([0, 0, 0], 0.9);
      ctx.fillStyle = rgb(colour, 0.6);
      const j = this.latestAction(i, this.tick);
      const act = j >= 0 ? this.action(this.actIndex[i][j]) : null;
      if (act && act.debug && typeof act.debug === 'object') {
        for (const value of Object.values(act.debug)) {
          if (isPoint(value)) { if (inside(value)) mark(value, 4, true); }
          else if (Array.isArray(value) && value.length <= 2000) {
            for (const p of value) if (isPoint(p) && inside(p)) mark(p, 2.5, true);
          }
        }
      }
      const goal = this.currentGoal(i, this.tick);
      if (goal && inside(goal)) {
        const [gx, gy] = this.worldToCanvas(goal[0], goal[1]);
        const [x, y] = this.worldToCanvas(...this.pose(i));
        ctx.setLineDash([4, 3]); ctx.strokeStyle = rgb(colour, 0.9);
        ctx.beginPath(); ctx.moveTo(x, y); ctx.lineTo(gx, gy); ctx.stroke(); ctx.setLineDash([]);
        ctx.strokeStyle = '#000'; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.moveTo(gx - 6, gy - 6); ctx.lineTo(gx + 6, gy + 6);
        ctx.moveTo(gx + 6, gy - 6); ctx.lineTo(gx - 6, gy + 6); ctx.stroke();
      }
    }

    drawRobots() {
      const ctx = this.ctx, r = this.robotPx;
      const order = [...Array(this.rec.R).keys()];
      if (this.selectedRobot !== null) { order.splice(this.selectedRobot, 1); order.push(this.selectedRobot); }
      ctx.font = '10px sans-serif';
      for (const i of order) {
        const [x, y, theta] = this.pose(i);
        const [cx, cy] = this.worldToCanvas(x, y);
        if (i === this.selectedRobot) {
          ctx.lineWidth = 3; ctx.strokeStyle = '#111';
          ctx.beginPath(); ctx.arc(cx, cy, r + 4, 0, 2 * Math.PI); ctx.stroke();
        }
        ctx.fillStyle = rgb(this.colour(i));
        ctx.strokeStyle = '#000'; ctx.lineWidth = 1;
        ctx.beginPath(); ctx.arc(cx, cy, r, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
        // heading: from the rim outwards, so the disc's centre keeps the robot's colour
        const dx = Math.cos(theta), dy = -Math.sin(theta);
        ctx.lineWidth = 2;
        ctx.beginPath(); ctx.moveTo(cx + 0.55 * r * dx, cy + 0.55 * r * dy); ctx.lineTo(cx + 1.7 * r * dx, cy + 1.7 * r * dy);
        ctx.stroke();
        ctx.fillStyle = '#000';
        ctx.fillText(String(i), cx + r + 2, cy - r - 1);
      }
    }

    drawCurve() {
      const c = this.curve, ctx = c.getContext('2d');
      const w = c.width, h = c.height, pad = 24, T = this.rec.T;
      ctx.clearRect(0, 0, w, h);
      const X = (t) => pad + (w - pad - 6) * (T > 1 ? t / (T - 1) : 0);
      const Y = (v) => h - 16 - (h - 26) * v;
      ctx.strokeStyle = '#ccc'; ctx.lineWidth = 1; ctx.font = '10px sans-serif'; ctx.fillStyle = '#666';
      for (const v of [0, 0.5, 1]) {
        ctx.beginPath(); ctx.moveTo(pad, Y(v)); ctx.lineTo(w - 6, Y(v)); ctx.stroke();
        ctx.fillText(Math.round(v * 100) + '%', 0, Y(v) + 3);
      }
      ctx.fillText('tick ' + (T - 1), w - 60, h - 3);
      const series = [[this.rec.explored, [31, 119, 180], 'explored'], [this.rec.coverage, [255, 127, 14], 'coverage']];
      const stride = Math.max(1, Math.floor(T / (2 * w)));
      for (const [values, colour] of series) {
        for (const [upto, alpha, width] of [[T - 1, 0.25, 1], [this.tick, 1, 2]]) {
          ctx.strokeStyle = rgb(colour, alpha); ctx.lineWidth = width;
          ctx.beginPath();
          for (let t = 0; t <= upto; t += stride) (t === 0 ? ctx.moveTo : ctx.lineTo).call(ctx, X(t), Y(values[t]));
          ctx.lineTo(X(upto), Y(values[upto]));
          ctx.stroke();
        }
      }
      ctx.strokeStyle = '#333'; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.moveTo(X(this.tick), 4); ctx.lineTo(X(this.tick), h - 16); ctx.stroke();
      ctx.fillStyle = rgb([31, 119, 180]); ctx.fillText('explored', pad + 4, 12);
      ctx.fillStyle = rgb([255, 127, 14]); ctx.fillText('coverage', pad + 60, 12);
    }

    linkCount() {
      let n = 0;
      for (const v of this.state.link) n += v;
      return n;
    }

    updateReadout() {
      const t = this.tick, off = this.rec.off.msg;
      document.getElementById('readout').textContent =
        `tick ${t} / ${this.rec.T - 1} (${(t * this.head.tick_s).toFixed(1)} s) · explored ` +
        `${(100 * this.rec.explored[t]).toFixed(1)} % · coverage ${(100 * this.rec.coverage[t]).toFixed(1)} % · ` +
        `${this.linkCount()} links · ${off[t + 1] - off[t]} messages sent` +
        (this.rec.hasComm
          ? ` · ${this.lostCount(t)} deliveries lost · ${plural(this.groups().length, 'group')}` : '');
    }

    lostCount(t) {
      const m = this.rec.msg, off = this.rec.off.msg;
      return m.lostOff[off[t + 1]] - m.lostOff[off[t]];
    }

    updatePanel(i) {
      const R = this.rec.R, t = this.tick;
      const free = this.state.counts[3 * i + FREE], solid = this.state.counts[3 * i + SOLID];
      const totals = this.messageTotals, at = t * R + i;
      const sent = totals.sent[at], bytes = totals.bytes[at], received = totals.received[at];
      const [x, y, theta] = this.pose(i);
      const goal = this.currentGoal(i, t);
      const j = this.latestAction(i, t);
      const act = j >= 0 ? this.action(this.actIndex[i][j]) : null;
      const c = this.colour(i);
      document.getElementById('robot-title').innerHTML =
        `<span class="swatch" style="background:${rgb(c)}"></span>Robot ${i}`;
      const rows = [
        ['position', `${fmt(x)}, ${fmt(y)} m`], ['heading', `${fmt(theta * 180 / Math.PI, 1)}°`],
        ['knows', `${free} free + ${solid} wall cells`],
        ['goal', goal ? `${fmt(goal[0])}, ${fmt(goal[1])} m` : '—'],
        ['messages', `${sent} sent (${bytes} B), ${received} received`],
        ...(this.rec.hasComm ? this.commFacts(i) : []),
        ['action', act === null ? (j >= 0 ? 'none (agent failed)' : '—') :
          (act.velocity ? `velocity ${fmt(act.velocity[0])} m/s, ${fmt(act.velocity[1])} rad/s` : 'navigate')],
      ];
      document.getElementById('robot-facts').innerHTML =
        rows.map(([k, v]) => `<tr><td>${k}</td><td>${escapeHtml(v)}</td></tr>`).join('');
      const heard = [];
      for (let s = 0; s < R; s++) {
        if (s !== i && this.state.link[i * R + s]) heard.push(`${s} (${fmt(this.margin(i, s), 1)} dB margin)`);
      }
      document.getElementById('robot-links').textContent = heard.length ? heard.join(', ') : 'nobody';
      document.getElementById('robot-debug').textContent =
        act && act.debug !== null && act.debug !== undefined ? JSON.stringify(act.debug, null, 1) : '(none)';
    }

    /** The robot panel's communication rows: its group, last contact, and how old its information about
     *  each other robot is. */
    commFacts(i) {
      const R = this.rec.R, t = this.tick, tickS = this.head.tick_s, c = this.commState()[i];
      const mates = this.groups().find((g) => g.includes(i)).filter((j) => j !== i);
      const ages = [];
      for (let s = 0; s < R; s++) {
        if (s !== i) ages.push(`${s}: ${((t - this.state.mergedAt[i * R + s]) * tickS).toFixed(1)} s`);
      }
      return [['group', mates.length ? `with ${mates.join(', ')}` : 'alone'],
              ['last contact', `${(c.since * tickS).toFixed(1)} s ago`],
              ['missing', `${(100 * c.missing).toFixed(1)} % of the team's free cells`],
              ['info age', `${(c.age * tickS).toFixed(1)} s on average; ${ages.join(', ')}`]];
    }

    renderLegend() {
      const present = new Set(this.rec.material);
      const items = [];
      for (const m of [...present].sort((a, b) => a - b)) {
        if (m === 0) continue;
        items.push(`<span><span class="swatch" style="background:${rgb(this.colours[m])}"></span>${escapeHtml(this.head.materials[m])}</span>`);
      }
      const ramp = RAMP.map(([v, c]) => `${rgb(c)} ${(v / 40) * 100}%`).join(',');
      items.push(`<span>link margin 0<span class="ramp" style="background:linear-gradient(90deg,${ramp})"></span>40 dB` +
                 ` (dashed: one way)</span>`);
      for (const name of this.rec.msg.types) {
        items.push(`<span><span class="swatch" style="background:${rgb(typeColour(name))}"></span>${escapeHtml(name)}</span>`);
      }
      document.getElementById('legend').innerHTML = items.join('');
      const totals = new Map();
      for (const code of this.rec.msg.lostCause) totals.set(code, (totals.get(code) || 0) + 1);
      const lost = [...totals.keys()].sort().map((code) => {
        const cause = this.rec.causes[code];
        return `<label title="${escapeHtml(causeText(cause))}"><input type="checkbox" data-cause="${escapeHtml(cause)}" checked>` +
          `<span class="lost-key" style="border-color:${rgb(causeColour(cause))}"></span>${escapeHtml(cause)} ` +
          `(${totals.get(code)})</label>`;
      });
      const box = document.getElementById('lost-legend');
      box.innerHTML = this.rec.hasComm
        ? (lost.length ? '<span>lost deliveries (select a robot for its own):</span>' + lost.join('')
          : '<span>no delivery was lost in this run</span>')
        : '<span>format version 1: no lost messages, groups or age of information recorded</span>';
      for (const input of box.querySelectorAll('input[data-cause]')) {
        input.addEventListener('change', () => {
          if (input.checked) this.hiddenCauses.delete(input.dataset.cause); else this.hiddenCauses.add(input.dataset.cause);
          this.draw();
        });
      }
      document.getElementById('aoi-panel').hidden = !this.rec.hasComm;
      const s = this.rec.tail.summary || {};
      const bits = [`${this.rec.R} robots`, `${this.rec.W} × ${this.rec.H} cells`, `radio ${this.head.radio_model}`];
      if (s.stop_reason) bits.push(`stopped at tick ${s.ticks} (${s.stop_reason})`);
      document.getElementById('subtitle').textContent = bits.join(' · ');
    }

    api() {
      const v = this;
      return {
        ready: true,
        nRobots: v.rec.R,
        nTicks: v.rec.T,
        lastTick: v.rec.T - 1,
        setTick: (t) => v.setTick(t),
        tick: () => v.tick,
        play: () => v.play(),
        pause: () => v.pause(),
        isPlaying: () => v.playing,
        select: (i) => v.select(i),
        selected: () => v.selectedRobot,
        pose: (i, t) => v.pose(i, t === undefined ? v.tick : t),
        worldToCanvas: (x, y) => v.worldToCanvas(x, y),
        robotScreenPosition: (i) => v.robotScreenPosition(i),
        robotColour: (i) => v.colour(i).slice(),
        explored: (t) => v.rec.explored[t === undefined ? v.tick : t],
        linkCount: () => v.linkCount(),
        knownCell: (i, row, col) => v.state.known[(i * v.rec.H + row) * v.rec.W + col],
        seenCell: (row, col) => v.state.seen[row * v.rec.W + col],
        hasComm: v.rec.hasComm,
        groups: () => v.groups(),
        aoi: () => v.commState(),
        drawnLosses: () => v.drawn.losses.map((d) => ({ ...d })),
        drawnGroups: () => v.drawn.groups.map((g) => ({ members: g.members.slice(), colour: g.colour.slice(),
                                                        hull: g.hull.map((p) => p.slice()) })),
        causeColour: (cause) => causeColour(cause).slice(),
        trailRange: () => v.trailRange.slice(),
        tooltipAt: (cx, cy) => { v.showTip(cx, cy, 0, 0); return v.tip.hidden ? '' : v.tip.textContent; },
      };
    }
  }

  async function main() {
    const status = document.getElementById('status');
    try {
      const cfg = JSON.parse(document.getElementById('swr-config').textContent);
      const bytes = base64ToBytes(document.getElementById('swr-data').textContent);
      const rec = await parseRecording(bytes);
      const viewer = new Viewer(rec, cfg);
      window.swarmViewer = viewer.api();
      status.textContent = '';
      document.body.dataset.ready = '1';
    } catch (err) {
      status.textContent = 'Cannot show this recording: ' + (err && err.message ? err.message : err);
      document.body.dataset.ready = 'error';
      throw err;
    }
  }

  main();
})();
