/* swarm replay viewer: decodes the .swr recording embedded in this page and draws it on a canvas.
 *
 * No libraries and nothing fetched: the recording is base64 in <script class="swr-data"> elements (pieces
 * of at most 48 MiB: a browser's strings stop at 512 MiB), its chunks are
 * zlib streams inflated with the browser's DecompressionStream, their bodies msgpack (decoded below).
 * The format is docs/recording-format.md; the Python reader is swarm/record/reader.py.
 *
 * Version 2 recordings add the communication streams: failed deliveries with their cause, the tick's groups,
 * map merges (age of information) and contacts; version 1 files still play, without those layers.
 *
 * At swarm size (issue 47) the page holds the union map and one selected robot's map, not every robot's;
 * the largest streams are reduced block by block as they are read; a frame draws points beyond 64 robots
 * in view and budgets of links, flashes, losses and trail points; the wheel zooms, a drag pans.
 *
 * For tests and scripting, window.swarmViewer exposes setTick, select, pose, robotScreenPosition, zoomAt,
 * view, and what the last frame drew: drawnLosses(), drawnGroups(), drawnCounts(), aoi(), pointMode(),
 * with stateBytes() and each frame step's milliseconds, profile() (benchmarks/speed/bench_viewer.py).
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
  // Swarm size (issue 47): what a frame draws and the panels list is bounded, whatever the number of robots.
  const POINTS_ABOVE = 64;        // more robots than this: drawn as points, at most one per POINT_CELL square
  const POINT_CELL = 3;           // pixels: the decimation grid of the point mode
  const LINK_BUDGET = 2500;       // links drawn at most (an even sample of them beyond)
  const MESSAGE_BUDGET = 2500;    // message flashes (sender to receiver lines) drawn at most
  const RING_BUDGET = 300;        // rings around transmitters drawn at most (overlapping rings rasterise slowly)
  const LOSS_BUDGET = 2500;       // failed deliveries drawn at most
  const TRAIL_BUDGET = 20000;     // trail points drawn at most, over all robots (600 each up to 33 robots)
  const AOI_ROWS = 16;            // age-of-information rows: every robot up to this, else the oldest
  const LIST_ITEMS = 24;          // robots listed in the robot panel's lists (links heard, ages, mates)
  const TOTALS_EVERY = 16;        // message totals are checkpointed every this many ticks
  const PAIR_AGES_UP_TO = 64;     // robots: up to this, the map-merge pairs are kept for the per-robot ages
  const MAX_ZOOM = 64;            // mouse wheel zoom: up to this many times the fitted map
  const ID_FONT_PX = 13;          // robot ids: bold, with a white halo
  const NICE_METRES = [0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];   // scale bar and grid steps

  // ------------------------------------------------------------------------------ decoding ----
  /** The recording from its base64 pieces (each a whole number of 3-byte groups), each dropped from the
   *  page once decoded: the text of a large recording would otherwise stay in memory beside its bytes.
   *  (atob skips whitespace itself.) */
  function embeddedBytes(elements) {
    const pieces = elements.map((e) => {
      const bin = atob(e.textContent);
      e.remove();
      const out = new Uint8Array(bin.length);
      for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
      return out;
    });
    return pieces.length === 1 ? pieces[0] : concat(pieces, Uint8Array);
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

  // The two largest streams at swarm size are reduced block by block to what the page shows, so neither
  // they nor the inflated blocks are ever all in memory (1,000 robots: ~1 MB a tick of the two, ~1.4 MB a
  // tick inflated; a 3,000-tick recording would not load).

  /** The map-merge stream (``merged_at[i, s]`` entries, every pair that merged) as the age of information
   *  needs it: per tick, each robot whose sum over s != i of merged_at[i, s] changed, and by how much (at
   *  most R a tick, against ~100,000 pair entries at 1,000 robots). Exact: integer differences in doubles. */
  class MergeSums {
    constructor(R) {
      this.R = R;
      this.merged = new Int32Array(R * R);   // the latest merged_at of each pair, while reading
      this.pending = new Float64Array(R);
      this.touched = new Uint8Array(R);
      this.parts = { n: [], robot: [], delta: [] };
    }

    /** One block: entries per tick, their flat indices i * R + s, their values. */
    add(counts, idx, val) {
      const R = this.R, n = new Uint32Array(counts.length), robot = [], delta = [], changed = [];
      let k = 0;
      for (let t = 0; t < counts.length; t++) {
        for (const end = k + counts[t]; k < end; k++) {
          const i = Math.floor(idx[k] / R), d = val[k] - this.merged[idx[k]];
          this.merged[idx[k]] = val[k];
          if (idx[k] === i * R + i || !d) continue;   // its own entry is not in its age
          if (!this.touched[i]) { this.touched[i] = 1; changed.push(i); }
          this.pending[i] += d;
        }
        for (const i of changed) { robot.push(i); delta.push(this.pending[i]); this.pending[i] = 0; this.touched[i] = 0; }
        n[t] = changed.length;
        changed.length = 0;
      }
      this.parts.n.push(n); this.parts.robot.push(Uint32Array.from(robot)); this.parts.delta.push(Float64Array.from(delta));
    }

    result(T) {
      const p = this.parts;
      return { off: p.n.length ? prefix(concat(p.n, Uint32Array)) : new Float64Array(T + 1),
               robot: concat(p.robot, Uint32Array), delta: concat(p.delta, Float64Array) };
    }
  }

  /** The deliveries (each message's receivers) as the page shows them: per tick, how many messages each
   *  robot received (the robot panel's totals), and an even sample of at most MESSAGE_BUDGET receivers a
   *  tick to flash (drawMessages samples the window's again). 1,000 robots: ~100,000 deliveries a tick,
   *  of which ~1,000 counts and 2,500 receivers are kept. */
  class Deliveries {
    constructor(R) {
      this.pending = new Float64Array(R);
      this.parts = { n: [], robot: [], count: [], shownN: [], shown: [] };
    }

    /** One block: messages per tick, receivers per message, the receivers back to back. */
    add(msgN, recvN, recv) {
      const pending = this.pending, n = new Uint32Array(msgN.length), shownN = new Uint32Array(recvN.length);
      const robot = [], count = [], shown = [], changed = [];
      let m = 0, q = 0;
      for (let t = 0; t < msgN.length; t++) {
        let total = 0;
        for (let j = m; j < m + msgN[t]; j++) total += recvN[j];
        const every = Math.max(1, Math.ceil(total / MESSAGE_BUDGET)), first = q;
        for (const end = m + msgN[t]; m < end; m++) {
          for (const stop = q + recvN[m]; q < stop; q++) {
            const r = recv[q];
            if (!pending[r]) changed.push(r);
            pending[r]++;
            if ((q - first) % every === 0) { shown.push(r); shownN[m]++; }
          }
        }
        for (const r of changed) { robot.push(r); count.push(pending[r]); pending[r] = 0; }
        n[t] = changed.length;
        changed.length = 0;
      }
      const p = this.parts;
      p.n.push(n); p.robot.push(Uint32Array.from(robot)); p.count.push(Float64Array.from(count));
      p.shownN.push(shownN); p.shown.push(Uint16Array.from(shown));
    }

    result() {
      const p = this.parts;
      return { receivedOff: prefix(concat(p.n, Uint32Array)), receivedRobot: concat(p.robot, Uint32Array),
               receivedCount: concat(p.count, Float64Array), shownOff: prefix(concat(p.shownN, Uint32Array)),
               shown: concat(p.shown, Uint16Array) };
    }
  }

  /** A block's absolute indices of a stream: stored as indices (``X_idx``), or from version 3 as per-tick
   *  gaps (``X_gap``, counted by ``X_n``). */
  function blockIndices(b, stream, gapped) {
    return gapped ? ungap(typed(b[stream + '_gap']), prefix(typed(b[stream + '_n']))) : typed(b[stream + '_idx']);
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
      chunks.push([kind, payload]);   // inflated one at a time below: all at once is 1.4 MB a tick at 1,000 robots
      pos += 12 + length;
    }
    if (!chunks.length || chunks[0][0] !== 'HEAD' || chunks[chunks.length - 1][0] !== 'TAIL') {
      throw new Error('incomplete recording');
    }
    const head = unpackMsgpack(await inflate(chunks[0][1]));
    const tail = unpackMsgpack(await inflate(chunks[chunks.length - 1][1]));
    if (!READABLE_VERSIONS.includes(head.version)) {
      throw new Error(`format version ${head.version}; this viewer knows ${READABLE_VERSIONS.join(', ')}`);
    }
    const hasComm = head.version >= 2;
    // version 3: link, RSSI and merge indices stored as per-tick gaps; msg_rssi as differences from the RSSI
    // stream (no view shows it)
    const gapped = head.version >= 3;
    const R = head.n_robots, H = head.shape[0], W = head.shape[1];
    const T = tail.ticks;
    const keepPairs = R <= PAIR_AGES_UP_TO;   // the map-merge pairs, for the robot panel's list of ages
    const commStreams = ['group', 'aoi', 'contact'];
    const streams = ['known', 'seen', 'link', 'rssi', 'msg', 'act', ...(hasComm ? commStreams : [])];
    const commArrays = ['msg_via', 'msg_lost_n', 'msg_lost', 'msg_lost_cause', 'group_robot', 'group_id',
                        ...(keepPairs ? ['aoi_idx', 'aoi_val'] : []), 'contact_robot', 'team_free'];
    // not msg_recv, msg_rssi (no view shows the latter): Deliveries reduces the receivers block by block
    const arrays = ['pose', 'metrics', 'known_gap', 'known_val', 'seen_gap', 'link_idx', 'rssi_idx', 'rssi_val',
                    'msg_sender', 'msg_seq', 'msg_type', 'msg_size', 'msg_recv_n',
                    'act_robot', ...streams.map((s) => s + '_n'), ...(hasComm ? commArrays : [])];
    const parts = {};
    for (const name of arrays) parts[name] = [];
    const typeNames = [], typeCode = {}, msgTypeParts = [], acts = [];
    const merges = new MergeSums(R), deliveries = new Deliveries(R);
    for (const [, payload] of chunks.slice(1, -1)) {
      const b = unpackMsgpack(await inflate(payload));
      if (gapped) Object.assign(b, { link_idx: b.link_gap, rssi_idx: b.rssi_gap, aoi_idx: b.aoi_gap });
      for (const name of arrays) parts[name].push(typed(b[name]));
      if (hasComm) merges.add(typed(b.aoi_n), blockIndices(b, 'aoi', gapped), typed(b.aoi_val));
      deliveries.add(typed(b.msg_n), typed(b.msg_recv_n), typed(b.msg_recv));
      const local = b.msg_types.map((name) => {
        if (!(name in typeCode)) { typeCode[name] = typeNames.length; typeNames.push(name); }
        return typeCode[name];
      });
      const codes = parts.msg_type[parts.msg_type.length - 1];
      msgTypeParts.push(Uint16Array.from(codes, (c) => local[c]));
      // copied: a view would keep the block's whole inflated chunk alive (1.4 MB a tick at 1,000 robots)
      for (const a of b.act) acts.push(a instanceof Uint8Array ? a.slice() : a);
    }
    const cat = {};
    for (const name of arrays) cat[name] = concat(parts[name], parts[name].length ? parts[name][0].constructor : Uint8Array);
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
    const knownIdx = ungap(cat.known_gap, off.known);
    const actTick = new Uint32Array(acts.length);
    for (let t = 0; t < T; t++) for (let k = off.act[t]; k < off.act[t + 1]; k++) actTick[k] = t;
    return {
      head, tail, R, H, W, T, off, explored, coverage, hasComm,
      poses: cat.pose, material: typed(head.material),
      knownIdx, knownVal: cat.known_val, knownPrev: previousValues(knownIdx, cat.known_val, R, H * W),
      seenIdx: ungap(cat.seen_gap, off.seen), linkIdx: gapped ? ungap(cat.link_idx, off.link) : cat.link_idx,
      rssiIdx: gapped ? ungap(cat.rssi_idx, off.rssi) : cat.rssi_idx, rssiVal: cat.rssi_val,
      msg: { sender: cat.msg_sender, seq: cat.msg_seq, type: concat(msgTypeParts, Uint16Array), size: cat.msg_size,
             recvOff: prefix(cat.msg_recv_n), ...deliveries.result(), tick: msgTick, types: typeNames,
             via: cat.msg_via, lostOff: prefix(cat.msg_lost_n), lost: cat.msg_lost, lostCause: cat.msg_lost_cause },
      causes: head.loss_causes || [],
      group: { robot: cat.group_robot, id: cat.group_id },
      aoi: keepPairs ? { idx: gapped ? ungap(cat.aoi_idx, off.aoi) : cat.aoi_idx, val: cat.aoi_val } : null,
      mergeSums: merges.result(T),
      contact: { robot: cat.contact_robot },
      teamFree: cat.team_free,
      act: { robot: cat.act_robot, data: acts, tick: actTick, decoded: new Map() },
    };
  }

  // ------------------------------------------------------------------------------ state ----
  /** Per knowledge-stream entry, the value the cell had before it (what the entry overwrote), so the
   *  per-robot cell counts can be kept without holding every robot's map (R*H*W bytes: 1.4 GB for 1,000
   *  robots on a 600-tile map). One counting sort by robot, then one scratch map of H*W reused robot after
   *  robot: O(entries) time, N bytes kept. */
  function previousValues(idx, val, R, cells) {
    const n = idx.length, start = new Uint32Array(R + 1);
    for (let k = 0; k < n; k++) start[Math.floor(idx[k] / cells) + 1]++;
    for (let r = 0; r < R; r++) start[r + 1] += start[r];
    const order = new Uint32Array(n), fill = start.slice(0, R);
    for (let k = 0; k < n; k++) order[fill[Math.floor(idx[k] / cells)]++] = k;   // stable: by tick within a robot
    const prev = new Uint8Array(n), scratch = new Uint8Array(cells);
    for (let r = 0; r < R; r++) {
      const base = r * cells;
      for (let p = start[r]; p < start[r + 1]; p++) {
        const k = order[p], c = idx[k] - base;
        prev[k] = scratch[c]; scratch[c] = val[k];
      }
      for (let p = start[r]; p < start[r + 1]; p++) scratch[idx[order[p]] - base] = UNSEEN;
    }
    return prev;
  }

  /** The first position in the sorted array ``a`` whose value is >= x. */
  function lowerBound(a, x) {
    let lo = 0, hi = a.length;
    while (lo < hi) { const mid = (lo + hi) >>> 1; if (a[mid] < x) lo = mid + 1; else hi = mid; }
    return lo;
  }

  /** The union seen raster, links, RSSI, per-robot cell counts and the communication state at one tick,
   *  with keyframes for fast seeking. No robot's own knowledge map: that is a RobotMap, built when a robot
   *  is selected. What remains grows with H*W and R*R (links and RSSI as the file stores them): ~8 MB per
   *  snapshot at 1,000 robots on 600 tiles. */
  class ReplayState {
    constructor(rec) {
      this.rec = rec;
      const { R, H, W, T } = rec;
      this.seen = new Uint8Array(H * W);
      this.link = new Uint8Array(Math.ceil(R * R / 8));   // a bit per (receiver, sender)
      this.rssi = new Int16Array(R * R);
      this.counts = new Float64Array(3 * R);           // per robot: cells UNSEEN, FREE, SOLID
      this.groupOf = new Int32Array(R);                // per robot: its group's smallest member
      this.mergedSum = new Float64Array(R);            // per robot i: the sum over s != i of merged_at[i, s]
      this.lastContact = new Float64Array(R);          // per robot: the last tick it received a message
      this.cells = H * W;
      this.reset();
      // keyframes within KEYFRAME_BUDGET; the first is the empty state before tick 0, made by reset(), not kept
      const snapshotBytes = H * W + this.link.length + 2 * R * R + 8 * 6 * R;
      const count = 1 + Math.floor(KEYFRAME_BUDGET / snapshotBytes);
      this.every = Math.max(32, Math.ceil(T / count));
      this.keyframes = [null];
      for (let t = 0; t < T; t++) {
        if (t % this.every === 0 && t > 0) this.keyframes.push(this.snapshot());
        this.apply(t);
      }
    }

    /** The state before tick 0: nothing seen or known, no links, no merges, no contact. */
    reset() {
      const R = this.rec.R;
      this.seen.fill(0); this.link.fill(0); this.rssi.fill(RSSI_NAN);
      this.counts.fill(0);
      for (let i = 0; i < R; i++) this.counts[3 * i] = this.cells;
      this.groupOf.fill(-1); this.mergedSum.fill(0); this.lastContact.fill(-1);
      this.links = 0;   // bits set in link: the readout's link count, O(1) a frame
      this.tick = -1;
    }

    snapshot() {
      return { tick: this.tick, links: this.links, seen: this.seen.slice(), link: this.link.slice(),
               rssi: this.rssi.slice(), counts: this.counts.slice(), groupOf: this.groupOf.slice(),
               mergedSum: this.mergedSum.slice(),
               lastContact: this.lastContact.slice() };
    }

    restore(k) {
      if (k === null) { this.reset(); return; }
      this.seen.set(k.seen); this.link.set(k.link); this.rssi.set(k.rssi);
      this.counts.set(k.counts); this.groupOf.set(k.groupOf);
      this.mergedSum.set(k.mergedSum); this.lastContact.set(k.lastContact);
      this.links = k.links;
      this.tick = k.tick;
    }

    /** Bytes held: the state and its keyframes. */
    bytes() {
      const arrays = (o) => Object.values(o).reduce((n, a) => n + (a && a.byteLength ? a.byteLength : 0), 0);
      return arrays(this) + this.keyframes.reduce((n, k) => n + (k ? arrays(k) : 0), 0);
    }

    linked(receiver, sender) {
      const b = receiver * this.rec.R + sender;
      return (this.link[b >>> 3] >>> (b & 7)) & 1;
    }

    apply(t) {
      const r = this.rec, off = r.off, R = r.R;
      const counts = this.counts, cells = this.cells;
      for (let k = off.known[t]; k < off.known[t + 1]; k++) {
        const base = 3 * Math.floor(r.knownIdx[k] / cells);
        counts[base + r.knownPrev[k]]--;
        counts[base + r.knownVal[k]]++;
      }
      for (let k = off.seen[t]; k < off.seen[t + 1]; k++) this.seen[r.seenIdx[k]] = 1;
      for (let k = off.link[t]; k < off.link[t + 1]; k++) {
        const b = r.linkIdx[k], bit = 1 << (b & 7);
        this.link[b >>> 3] ^= bit;
        this.links += this.link[b >>> 3] & bit ? 1 : -1;
      }
      for (let k = off.rssi[t]; k < off.rssi[t + 1]; k++) this.rssi[r.rssiIdx[k]] = r.rssiVal[k];
      for (let k = off.group[t]; k < off.group[t + 1]; k++) this.groupOf[r.group.robot[k]] = r.group.id[k];
      const sums = r.mergeSums;
      for (let k = sums.off[t]; k < sums.off[t + 1]; k++) this.mergedSum[sums.robot[k]] += sums.delta[k];
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

  /** One robot's knowledge map, rebuilt on demand from its entries in the knowledge stream: H*W bytes
   *  for the robot shown instead of R*H*W for all. Forward it applies the new entries; backward it starts
   *  again from an empty map, O(H*W + the robot's entries), a few milliseconds even on 600 tiles. */
  class RobotMap {
    constructor(rec, robot) {
      this.rec = rec;
      this.robot = robot;
      const cells = rec.H * rec.W, lo = robot * cells, hi = lo + cells, idx = rec.knownIdx;
      let n = 0;
      for (let k = 0; k < idx.length; k++) if (idx[k] >= lo && idx[k] < hi) n++;
      this.entries = new Uint32Array(n);   // positions in the stream, hence in tick order
      for (let k = 0, j = 0; k < idx.length; k++) if (idx[k] >= lo && idx[k] < hi) this.entries[j++] = k;
      this.base = lo;
      this.map = new Uint8Array(cells);
      this.done = 0;     // entries applied
      this.resets = 0;   // times it started again (a painter that follows it repaints everything)
      this.tick = -1;
    }

    seek(t) {
      if (t === this.tick) return;
      const end = lowerBound(this.entries, this.rec.off.known[t + 1]);
      if (end < this.done) { this.map.fill(UNSEEN); this.done = 0; this.resets++; }
      const idx = this.rec.knownIdx, val = this.rec.knownVal;
      for (let j = this.done; j < end; j++) { const k = this.entries[j]; this.map[idx[k] - this.base] = val[k]; }
      this.done = end;
      this.tick = t;
    }

    /** The cell (row * W + col) that the robot's j-th entry changed. */
    cellAt(j) { return this.rec.knownIdx[this.entries[j]] - this.base; }

    bytes() { return this.entries.byteLength + this.map.byteLength; }
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

  /** Items joined by commas, at most LIST_ITEMS of them, then "… and N more" and the note. */
  function listed(items, note) {
    const more = items.length - LIST_ITEMS;
    return items.slice(0, LIST_ITEMS).join(', ') + (more > 0 ? ` … and ${more} more` : '') + (note || '');
  }

  /** Sorted ids as ranges: [0, 1, 2, 3, 7] -> "0-3, 7". */
  function idRanges(ids) {
    const out = [];
    for (let k = 0; k < ids.length; k++) {
      let j = k;
      while (j + 1 < ids.length && ids[j + 1] === ids[j] + 1) j++;
      out.push(j > k ? `${ids[k]}–${ids[j]}` : String(ids[k]));
      k = j;
    }
    return out.join(', ');
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
      this.baseLast = null;   // what the map image shows: {key, tick, ...} (drawBase)
      this.actIndex = this.indexActions();
      this.checkpoints = this.messageCheckpoints();
      this.totalsCache = null;
      this.robotMaps = [];   // the RobotMaps built, most recent first (at most two: the selected robot's)
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

    /** Per robot, running totals of messages sent, bytes sent and messages received before every
     *  TOTALS_EVERY-th tick: 3 * R * T / TOTALS_EVERY numbers (a row per tick would be 72 MB at 1,000 robots
     *  and 3,000 ticks); messageTotals finishes the count from the checkpoint. */
    messageCheckpoints() {
      const { R, T, msg, off } = this.rec;
      const n = Math.ceil(T / TOTALS_EVERY) + 1;
      const sent = new Float64Array(n * R), bytes = new Float64Array(n * R), received = new Float64Array(n * R);
      const s = new Float64Array(R), b = new Float64Array(R), r = new Float64Array(R);
      for (let t = 0; t < T; t++) {
        if (t % TOTALS_EVERY === 0) {
          const at = (t / TOTALS_EVERY) * R;
          sent.set(s, at); bytes.set(b, at); received.set(r, at);
        }
        for (let k = off.msg[t]; k < off.msg[t + 1]; k++) {
          s[msg.via[k]]++; b[msg.via[k]] += msg.size[k];   // the transmitter (a relay sends copies)
        }
        for (let k = msg.receivedOff[t]; k < msg.receivedOff[t + 1]; k++) r[msg.receivedRobot[k]] += msg.receivedCount[k];
      }
      return { sent, bytes, received };
    }

    /** Robot i's messages sent, bytes sent and messages received up to tick t: from the checkpoint before
     *  t, or from the last answer when playback moved forward (one tick's messages a frame). */
    messageTotals(i, t) {
      const { R, msg, off } = this.rec;
      let c = this.totalsCache, from;
      if (c && c.robot === i && c.tick <= t && t - c.tick <= TOTALS_EVERY) {
        from = c.tick + 1;
        c = { ...c };
      } else {
        const at = Math.floor(t / TOTALS_EVERY);
        from = at * TOTALS_EVERY;
        const p = this.checkpoints;
        c = { robot: i, sent: p.sent[at * R + i], bytes: p.bytes[at * R + i], received: p.received[at * R + i] };
      }
      for (let k = off.msg[from]; k < off.msg[t + 1]; k++) if (msg.via[k] === i) { c.sent++; c.bytes += msg.size[k]; }
      for (let k = msg.receivedOff[from]; k < msg.receivedOff[t + 1]; k++) {
        if (msg.receivedRobot[k] === i) c.received += msg.receivedCount[k];
      }
      c.tick = t;
      this.totalsCache = c;
      return c;
    }

    /** Robot i's own knowledge map at the current tick (built on first use; the two most recent kept). */
    robotMap(i) {
      let m = this.robotMaps.find((x) => x.robot === i);
      if (!m) m = new RobotMap(this.rec, i);
      this.robotMaps = [m, ...this.robotMaps.filter((x) => x !== m)].slice(0, 2);
      m.seek(this.tick);
      return m;
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
      const side = document.getElementById('side');
      const aside = 350 + (side ? side.offsetWidth + 10 : 0), pad = 40;
      const maxW = Math.max(200, window.innerWidth - aside - pad);
      const maxH = Math.max(200, window.innerHeight - 80);
      this.cellPx = Math.max(0.5, Math.min(maxW / W, maxH / H));
      this.canvas.width = Math.max(1, Math.round(W * this.cellPx));
      this.canvas.height = Math.max(1, Math.round(H * this.cellPx));
      this.cellPx = this.canvas.width / W;
      this.canvas.style.width = this.canvas.width + 'px';
      this.canvas.style.height = this.canvas.height + 'px';
      this.setView(this.zoom || 1, this.offX || 0, this.offY || 0);
    }

    /** Zoom (1: the whole map fits; at most MAX_ZOOM) and the offset of the canvas into the zoomed map,
     *  clamped so the map always fills the canvas. */
    setView(zoom, offX, offY) {
      this.zoom = Math.min(MAX_ZOOM, Math.max(1, zoom));
      this.offX = Math.min(Math.max(0, offX), this.canvas.width * (this.zoom - 1));
      this.offY = Math.min(Math.max(0, offY), this.canvas.height * (this.zoom - 1));
      this.scaleRobots();
    }

    /** Zoom by ``factor`` keeping the canvas point (cx, cy) where it is. */
    zoomAt(factor, cx, cy) {
      const z = Math.min(MAX_ZOOM, Math.max(1, this.zoom * factor)), f = z / this.zoom;
      this.setView(z, (cx + this.offX) * f - cx, (cy + this.offY) * f - cy);
    }

    /** Points or discs: points when more than POINTS_ABOVE robots are in view at this tick (zoomed out on a
     *  swarm); discs otherwise, at least 4 pixels, growing with the zoom. The hit radius, group margins
     *  and message rings follow. */
    scaleRobots() {
      let inView = 0;
      if (this.rec.R > POINTS_ABOVE) {
        const w = this.canvas.width, h = this.canvas.height;
        for (let i = 0; i < this.rec.R && inView <= POINTS_ABOVE; i++) {
          const [x, y] = this.canvasXY(i);
          if (x >= 0 && y >= 0 && x < w && y < h) inView++;
        }
      }
      this.points = inView > POINTS_ABOVE;
      this.robotPx = this.points ? 2 : Math.max(4, this.head.robot_radius_m / this.cellM * this.cellPx * this.zoom);
    }

    worldToCanvas(x, y) {   // (at zoom 1 and offset 0 exactly the unzoomed arithmetic)
      return [x / this.cellM * this.cellPx * this.zoom - this.offX,
              (this.rec.H - y / this.cellM) * this.cellPx * this.zoom - this.offY];
    }

    /** Where robot i is drawn at tick t: worldToCanvas(pose(i, t)) without the intermediate arrays (called
     *  hundreds of thousands of times a frame at swarm size). */
    canvasXY(i, t = this.tick) {
      const k = (t * this.rec.R + i) * 3, p = this.rec.poses;
      return [p[k] / this.cellM * this.cellPx * this.zoom - this.offX,
              (this.rec.H - p[k + 1] / this.cellM) * this.cellPx * this.zoom - this.offY];
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
      document.getElementById('lost-window').textContent =
        `(last ${LOST_TICKS} ticks, ${(LOST_TICKS * this.head.tick_s).toFixed(1)} s)`;
      for (const id of ['show-links', 'show-messages', 'show-trails', 'show-debug', 'show-groups', 'show-lost',
                        'trail-fade', 'show-goals', 'show-ids', 'show-grid']) {
        document.getElementById(id).addEventListener('change', () => this.draw());
      }
      this.trailSeconds.addEventListener('input', () => this.draw());
      // wheel: zoom about the mouse; drag: pan (a drag is not a click); key 0: the whole map again
      this.canvas.addEventListener('wheel', (e) => {
        e.preventDefault();
        const rect = this.canvas.getBoundingClientRect();
        this.zoomAt(Math.exp(-e.deltaY * 0.002), e.clientX - rect.left, e.clientY - rect.top);
        this.draw();
      }, { passive: false });
      let drag = null;
      this.canvas.addEventListener('mousedown', (e) => {
        drag = { x: e.clientX, y: e.clientY, offX: this.offX, offY: this.offY, moved: false };
      });
      window.addEventListener('mouseup', () => { if (drag && !drag.moved) drag = null; });
      this.canvas.addEventListener('mousemove', (e) => {
        const rect = this.canvas.getBoundingClientRect();
        if (drag && e.buttons === 1 && this.zoom > 1) {
          const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
          if (drag.moved || Math.hypot(dx, dy) > 3) {
            drag.moved = true;
            this.setView(this.zoom, drag.offX - dx, drag.offY - dy);
            this.draw();
            return;
          }
        }
        this.showTip(e.clientX - rect.left, e.clientY - rect.top, e.clientX, e.clientY);
      });
      this.canvas.addEventListener('mouseleave', () => { this.tip.hidden = true; });
      this.canvas.addEventListener('click', (e) => {
        const dragged = drag && drag.moved;
        drag = null;
        if (dragged) return;
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
        if (e.key === '0') { this.setView(1, 0, 0); this.draw(); }
      });
      window.addEventListener('resize', () => { this.layout(); this.baseLast = null; this.trailTick = -1; this.draw(); });
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
      const a = performance.now();
      this.state.seek(t);
      this.seekMs = performance.now() - a;
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
    /** One frame. Each step's milliseconds (issuing the drawing, not rasterising it) are kept in
     *  this.profile for benchmarks/speed/bench_viewer.py, with the state's seek before it. */
    draw() {
      const profile = { seek: this.seekMs || 0 }, on = (id) => document.getElementById(id).checked;
      let clock = performance.now();
      const step = (name, run) => {
        run();
        const now = performance.now();
        profile[name] = now - clock;
        clock = now;
      };
      const ctx = this.ctx;
      this.drawn = { losses: [], groups: [], robots: 0, links: 0, messages: 0, goals: [], clusters: [], scale: null, grid: null };
      this.scaleRobots();
      step('base', () => {
        this.drawBase();
        ctx.imageSmoothingEnabled = false;
        ctx.drawImage(this.base, -this.offX, -this.offY, this.canvas.width * this.zoom, this.canvas.height * this.zoom);
      });
      if (on('show-grid')) step('grid', () => this.drawGrid());
      if (this.rec.hasComm && on('show-groups')) step('groups', () => this.drawGroups());
      if (on('show-trails')) step('trails', () => this.drawTrails());
      if (on('show-links')) step('links', () => this.drawLinks());
      if (on('show-messages')) step('messages', () => this.drawMessages());
      if (on('show-lost')) step('lost', () => this.drawLosses());
      if (on('show-goals') && !this.points) step('goals', () => this.drawGoals());
      if (this.selectedRobot !== null && on('show-debug')) step('debug', () => this.drawDebug(this.selectedRobot));
      step('robots', () => this.drawRobots(on('show-ids')));
      if (on('show-grid')) step('scale', () => this.drawScaleBar());
      step('curve', () => this.drawCurve());
      step('readout', () => this.updateReadout());
      step('aoi', () => this.updateAoi());
      if (this.selectedRobot !== null) step('panel', () => this.updatePanel(this.selectedRobot));
      this.profile = profile;
      this.seekMs = 0;
    }

    /** The map image (a pixel per cell): the union view, or the selected robot's own map. Played forward it
     *  repaints only the cells that changed since the last frame (newly seen, or the robot's new knowledge)
     *  and uploads only their bounding box: a full repaint is H*W cells, 1.4 million on 600 tiles. */
    drawBase() {
      const key = this.selectedRobot + ':' + this.canvas.width;
      const r = this.selectedRobot, rm = r === null ? null : this.robotMap(r);
      const last = this.baseLast;
      if (last && last.key === key && last.tick === this.tick) return;
      const { W, H } = this.rec;
      const full = !last || last.key !== key || this.tick < last.tick || last.rm !== rm || (rm && rm.resets !== last.resets);
      const changed = [];
      if (!full) {
        const off = this.rec.off.seen, seenIdx = this.rec.seenIdx;
        for (let k = off[last.tick + 1]; k < off[this.tick + 1]; k++) changed.push(seenIdx[k]);
        if (rm) for (let j = last.done; j < rm.done; j++) changed.push(rm.cellAt(j));
      }
      this.baseLast = { key, tick: this.tick, rm, done: rm ? rm.done : 0, resets: rm ? rm.resets : 0 };
      if (full || changed.length > W * H / 8) {
        for (let cell = 0; cell < W * H; cell++) this.paintCell(cell, rm);
        this.baseCtx.putImageData(this.image, 0, 0);
        return;
      }
      if (!changed.length) return;
      let x0 = W, x1 = -1, y0 = H, y1 = -1;
      for (const cell of changed) {
        this.paintCell(cell, rm);
        const x = cell % W, y = H - 1 - Math.floor(cell / W);
        if (x < x0) x0 = x; if (x > x1) x1 = x; if (y < y0) y0 = y; if (y > y1) y1 = y;
      }
      this.baseCtx.putImageData(this.image, 0, 0, x0, y0, x1 - x0 + 1, y1 - y0 + 1);
    }

    /** One cell's colour in the map image: by material, seen by anyone or not (union view), or by what the
     *  robot of RobotMap rm knows of it. */
    paintCell(cell, rm) {
      if (!this.palette) {
        const unseenFree = this.cfg.unseenFree, othersFree = this.cfg.othersFree;
        this.palette = { faded: this.colours.map((c) => mix(c, unseenFree, this.cfg.unseenWallFade)),
                         half: this.colours.map((c) => mix(c, othersFree, 0.35)) };
      }
      const { faded, half } = this.palette, W = this.rec.W, H = this.rec.H;
      const m = this.rec.material[cell], seen = this.state.seen[cell];
      let c;
      if (rm === null) {
        c = m ? (seen ? this.colours[m] : faded[m]) : (seen ? this.cfg.seenFree : this.cfg.unseenFree);
      } else {
        const k = rm.map[cell];
        if (k === SOLID) c = m ? this.colours[m] : this.colours[1] || [60, 60, 60];
        else if (k === FREE) c = this.cfg.seenFree;
        else if (seen) c = m ? half[m] : this.cfg.othersFree;
        else c = m ? faded[m] : this.cfg.unseenFree;
      }
      const p = ((H - 1 - Math.floor(cell / W)) * W + cell % W) * 4, data = this.image.data;
      data[p] = c[0]; data[p + 1] = c[1]; data[p + 2] = c[2]; data[p + 3] = 255;
    }

    /** Trails: the whole run's path, or the last N seconds of it (``trail-seconds``), fading with age
     *  (``trail-fade``): a faded or limited trail is redrawn every frame from at most TRAIL_POINTS points per
     *  robot (and TRAIL_BUDGET over all robots), in TRAIL_BANDS bands of equal age, the oldest faintest. In
     *  the point mode one path per colour and band, not a stroke per robot and band. */
    drawTrails() {
      const seconds = Math.max(0, Number(this.trailSeconds.value) || 0);
      const fade = this.trailFade.checked;
      if (!fade && !seconds) { this.drawWholeTrails(); return; }
      const t = this.tick, ctx = this.ctx;
      const from = seconds ? Math.max(0, t - Math.round(seconds / this.head.tick_s)) : 0;
      this.trailRange = [from, t];
      const span = t - from;
      if (span < 1) return;
      const perRobot = Math.max(2, Math.min(TRAIL_POINTS, Math.floor(TRAIL_BUDGET / this.rec.R)));
      const stride = Math.max(1, Math.ceil(span / perRobot));
      const bands = fade ? Math.min(TRAIL_BANDS, span) : 1;
      // a style per colour and band, and in the point mode a path per style (stroked once at the end)
      const nc = this.robotColours.length, styles = [], batched = this.points ? [] : null;
      for (let c = 0; c < Math.min(nc, this.rec.R); c++) {
        const colour = mix(this.robotColours[c], [255, 255, 255], 0.35);
        for (let b = 0; b < bands; b++) {
          styles.push(rgb(colour, fade ? 0.08 + 0.92 * (b + 1) / bands : 1));
          if (batched) batched.push(new Path2D());
        }
      }
      ctx.save();
      ctx.lineWidth = this.points ? 1 : 1.5; ctx.lineJoin = 'round'; ctx.lineCap = 'butt';
      for (let i = 0; i < this.rec.R; i++) {
        for (let b = 0; b < bands; b++) {
          const a = from + Math.floor(b * span / bands), z = from + Math.floor((b + 1) * span / bands);
          const style = (i % nc) * bands + b;
          let path = ctx;
          if (batched) {
            path = batched[style];
          } else {
            ctx.strokeStyle = styles[style];
            ctx.beginPath();
          }
          path.moveTo(...this.canvasXY(i, a));
          for (let s = (Math.floor(a / stride) + 1) * stride; s < z; s += stride) {
            path.lineTo(...this.canvasXY(i, s));
          }
          path.lineTo(...this.canvasXY(i, z));
          if (!batched) ctx.stroke();
        }
      }
      if (batched) batched.forEach((path, k) => { ctx.strokeStyle = styles[k]; ctx.stroke(path); });
      ctx.restore();
    }

    /** The whole run's trails, unfaded, live on their own canvas, extended incrementally as time moves
     *  forward (a full redraw of 16 long trails costs ~50 ms in software rendering; a few new segments cost
     *  nothing). */
    drawWholeTrails() {
      const t = this.tick, layer = this.trails;
      this.trailRange = [0, t];
      const view = [this.canvas.width, this.canvas.height, this.zoom, this.offX, this.offY].join();
      if (view !== this.trailView || t < this.trailTick) {   // drawn in canvas pixels: a new view starts again
        layer.width = this.canvas.width; layer.height = this.canvas.height;   // (also clears it)
        this.trailView = view;
        this.trailTick = -1;
      }
      if (t > this.trailTick) {
        const ctx = layer.getContext('2d');
        const from = Math.max(0, this.trailTick);
        const perRobot = Math.max(2, Math.min(1500, Math.floor(TRAIL_BUDGET / this.rec.R)));
        const stride = Math.max(1, Math.floor((t - from) / perRobot));
        ctx.lineWidth = this.points ? 1 : 1.5;
        ctx.lineJoin = 'round';
        ctx.lineCap = 'round';
        const paths = new Map();   // one per colour (opaque: the same pixels as a stroke per robot)
        for (let i = 0; i < this.rec.R; i++) {
          const style = rgb(mix(this.colour(i), [255, 255, 255], 0.35));
          if (!paths.has(style)) paths.set(style, new Path2D());
          const path = paths.get(style);
          let [x, y] = this.canvasXY(i, from);
          path.moveTo(x, y);
          for (let s = from + stride; s < t; s += stride) {
            [x, y] = this.canvasXY(i, s);
            path.lineTo(x, y);
          }
          [x, y] = this.canvasXY(i, t);
          path.lineTo(x, y);
        }
        for (const [style, path] of paths) { ctx.strokeStyle = style; ctx.stroke(path); }
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
        const hull = convexHull(members.map((i) => this.canvasXY(i)));
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
     *  line cost milliseconds a frame when 16 robots share maps out of reach). Beyond LOSS_BUDGET failed
     *  deliveries in the window, an even sample of them (every n-th). */
    drawLosses() {
      const ctx = this.ctx, m = this.rec.msg, off = this.rec.off.msg, causes = this.rec.causes;
      const sel = this.selectedRobot;
      const first = Math.max(0, this.tick - LOST_TICKS + 1);
      const every = sel !== null ? 1 : Math.max(1, Math.ceil((m.lostOff[off[this.tick + 1]] - m.lostOff[off[first]]) / LOSS_BUDGET));
      ctx.save();
      ctx.lineWidth = 2;
      for (let t = first; t <= this.tick; t++) {
        const lines = new Map();
        for (let k = off[t]; k < off[t + 1]; k++) {
          if (m.lostOff[k] === m.lostOff[k + 1]) continue;
          const from = m.via[k];
          const [sx, sy] = this.canvasXY(from);
          for (let q = m.lostOff[k]; q < m.lostOff[k + 1]; q++) {
            if (q % every) continue;
            const cause = causes[m.lostCause[q]], to = m.lost[q];
            if (this.hiddenCauses.has(cause) || (sel !== null && from !== sel && to !== sel)) continue;
            if (!lines.has(cause)) lines.set(cause, [new Path2D(), new Path2D()]);
            const [dashed, crosses] = lines.get(cause);
            const [rx, ry] = this.canvasXY(to);
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
          age = t - st.mergedSum[i] / (R - 1);
          since = t - Math.max(st.lastContact[i], 0);
          if (team > 0) missing = Math.min(Math.max(1 - st.counts[3 * i + FREE] / team, 0), 1);
        }
        out.push({ robot: i, group: st.groupOf[i], age, since, missing });
      }
      return out;
    }

    /** The age-of-information panel: a row per robot, bars scaled to the largest age at this tick; with
     *  more than AOI_ROWS robots, the AOI_ROWS with the oldest information (and the selected robot). */
    updateAoi() {
      const body = document.getElementById('aoi-rows');
      if (!this.rec.hasComm) return;
      const all = this.commState(), tickS = this.head.tick_s;
      const sizes = new Map();
      let scale = 10;
      for (const r of all) { sizes.set(r.group, (sizes.get(r.group) || 0) + 1); scale = Math.max(scale, r.age); }
      let rows = all;
      if (all.length > AOI_ROWS) {
        rows = all.slice().sort((a, b) => b.age - a.age || a.robot - b.robot).slice(0, AOI_ROWS);
        const sel = this.selectedRobot;
        if (sel !== null && !rows.some((r) => r.robot === sel)) rows.push(all[sel]);
      }
      document.getElementById('aoi-note').textContent = rows === all ? ''
        : `the ${AOI_ROWS} of ${all.length} robots with the oldest information` +
          (rows.length > AOI_ROWS ? ', and the selected one' : '');
      const ids = rows.map((r) => r.robot).join(',');
      if (body.dataset.robots !== ids) {
        body.dataset.robots = ids;
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

    /** Links, coloured by the weaker direction's RSSI margin, dashed when one way. Beyond LINK_BUDGET only
     *  an even sample (every n-th pair) is drawn, and in the point mode in one thin path per colour band: a
     *  stroke per link costs microseconds, and 1,000 robots in reach of each other have half a million. */
    drawLinks() {
      const ctx = this.ctx, R = this.rec.R, st = this.state, bits = st.link;
      const every = Math.max(1, Math.ceil(st.links / 2 / LINK_BUDGET));
      const batched = this.points ? new Map() : null;
      ctx.lineWidth = this.points ? 1 : 2.5;
      let pairs = 0, drawn = 0;
      const draw = (i, j, ij, ji) => {
        let m = Infinity;
        if (ij) m = Math.min(m, this.margin(i, j));
        if (ji) m = Math.min(m, this.margin(j, i));
        const [xi, yi] = this.canvasXY(i), [xj, yj] = this.canvasXY(j);
        const colour = rgb(rampColour(isFinite(m) ? m : 40), 0.85);
        drawn++;
        if (batched) {
          const band = (ij && ji ? 's' : 'd') + Math.round(isFinite(m) ? Math.min(40, Math.max(0, m)) / 5 : 8);
          if (!batched.has(band)) batched.set(band, [colour, ij && ji, new Path2D()]);
          const path = batched.get(band)[2];
          path.moveTo(xi, yi); path.lineTo(xj, yj);
          return;
        }
        ctx.strokeStyle = colour;
        ctx.setLineDash(ij && ji ? [] : [6, 4]);
        ctx.beginPath(); ctx.moveTo(xi, yi); ctx.lineTo(xj, yj); ctx.stroke();
      };
      const bit = (b) => (bits[b >>> 3] >>> (b & 7)) & 1;
      if (st.links < R * R / 8) {
        // sparse (a spread swarm): each set bit once, zero bytes skipped; bit r * R + s is "r hears s", and
        // the pair {i < j} is taken at bit i * R + j if set, else at j * R + i (a one-way link)
        scan: for (let byte = 0; byte < bits.length; byte++) {
          for (let v = bits[byte]; v; v &= v - 1) {
            const b = byte * 8 + 31 - Math.clz32(v & -v);
            const r = Math.floor(b / R), s = b - r * R, i = Math.min(r, s), j = Math.max(r, s);
            if (i === j || (r > s && bit(i * R + j))) continue;
            if (pairs++ % every) continue;
            if (drawn === LINK_BUDGET) break scan;
            draw(i, j, bit(i * R + j), bit(j * R + i));
          }
        }
      } else {
        // dense (a gathered swarm): every pair, R * R / 2 tests, cheaper than visiting every set bit
        pairs: for (let i = 0; i < R; i++) {
          for (let j = i + 1; j < R; j++) {
            const ij = bit(i * R + j), ji = bit(j * R + i);
            if (!ij && !ji) continue;
            if (pairs++ % every) continue;
            if (drawn === LINK_BUDGET) break pairs;
            draw(i, j, ij, ji);
          }
        }
      }
      if (batched) {
        for (const [colour, both, path] of batched.values()) {
          ctx.strokeStyle = colour; ctx.setLineDash(both ? [] : [3, 2]); ctx.stroke(path);
        }
      }
      ctx.setLineDash([]);
      this.drawn.links = drawn;
    }

    drawMessages() {
      const ctx = this.ctx, m = this.rec.msg, off = this.rec.off.msg;
      const first = Math.max(0, this.tick - FLASH_TICKS + 1);
      const lineEvery = Math.max(1, Math.ceil((m.shownOff[off[this.tick + 1]] - m.shownOff[off[first]]) / MESSAGE_BUDGET));
      const ringEvery = Math.max(1, Math.ceil((off[this.tick + 1] - off[first]) / RING_BUDGET));
      const paths = new Map();   // one path per style (type, age, line or ring): a few strokes a frame
      const path = (kind, style, width) => {
        const key = kind + style;
        if (!paths.has(key)) paths.set(key, [style, width, new Path2D()]);
        return paths.get(key)[2];
      };
      let drawn = 0;
      for (let k = off[first]; k < off[this.tick + 1]; k++) {
        const age = this.tick - m.tick[k];
        const alpha = 1 - age / FLASH_TICKS;
        const colour = typeColour(m.types[m.type[k]]);
        const [sx, sy] = this.canvasXY(m.via[k]);
        const f = Math.min(1, (age + 1) / 3);   // the flash travels from sender to receiver
        const q0 = m.shownOff[k] + (lineEvery - m.shownOff[k] % lineEvery) % lineEvery;
        for (let q = q0; q < m.shownOff[k + 1]; q += lineEvery) {
          const [rx, ry] = this.canvasXY(m.shown[q]);
          const lines = path('line', rgb(colour, 0.8 * alpha), this.points ? 1 : 2);
          lines.moveTo(sx, sy); lines.lineTo(sx + f * (rx - sx), sy + f * (ry - sy));
          drawn++;
        }
        if (k % ringEvery) continue;
        const delivered = m.recvOff[k + 1] > m.recvOff[k];
        const radius = this.robotPx + 3 + 2 * age;
        const ring = path('ring', delivered ? rgb(colour, alpha) : rgb([120, 120, 120], alpha), 2);
        ring.moveTo(sx + radius, sy); ring.arc(sx, sy, radius, 0, 2 * Math.PI);
      }
      for (const [style, width, p] of paths.values()) { ctx.lineWidth = width; ctx.strokeStyle = style; ctx.stroke(p); }
      this.drawn.messages = drawn;
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
        const [x, y] = this.canvasXY(i);
        ctx.setLineDash([4, 3]); ctx.strokeStyle = rgb(colour, 0.9);
        ctx.beginPath(); ctx.moveTo(x, y); ctx.lineTo(gx, gy); ctx.stroke(); ctx.setLineDash([]);
        ctx.strokeStyle = '#000'; ctx.lineWidth = 2;
        ctx.beginPath(); ctx.moveTo(gx - 6, gy - 6); ctx.lineTo(gx + 6, gy + 6);
        ctx.moveTo(gx + 6, gy - 6); ctx.lineTo(gx - 6, gy + 6); ctx.stroke();
      }
    }

    drawRobots(ids = true) {
      if (this.points) { this.drawPoints(); return; }
      const ctx = this.ctx, r = this.robotPx;
      const order = [...Array(this.rec.R).keys()];
      if (this.selectedRobot !== null) { order.splice(this.selectedRobot, 1); order.push(this.selectedRobot); }
      const clusters = this.clusters(), inCluster = new Set(clusters.flat());
      ctx.font = `bold ${ID_FONT_PX}px sans-serif`;
      for (const i of order) this.drawDisc(i, r, ids && !inCluster.has(i));
      for (const members of clusters) this.drawCluster(members, ids);
      this.drawn.robots = this.rec.R;
      this.drawn.clusters = clusters;
    }

    /** Robots drawn too close to read (discs and ids overlap: centres nearer than a diameter plus an id's
     *  height), as lists of ids in order, each of two or more: at tick 0 a team spawned together is one
     *  cluster. Single-link grouping over the robots in view (disc mode: at most POINTS_ABOVE of them, so
     *  a zoomed-in swarm costs O(R) here, not O(R^2)). */
    clusters() {
      const near = 2 * this.robotPx + ID_FONT_PX, shown = this.inView(near);
      const parent = shown.map((_, k) => k), xy = shown.map((i) => this.canvasXY(i));
      const find = (k) => { while (parent[k] !== k) k = parent[k] = parent[parent[k]]; return k; };
      for (let a = 0; a < shown.length; a++) {
        for (let b = a + 1; b < shown.length; b++) {
          if (Math.hypot(xy[a][0] - xy[b][0], xy[a][1] - xy[b][1]) < near) parent[find(b)] = find(a);
        }
      }
      const by = new Map();
      shown.forEach((i, k) => {
        const root = find(k);
        if (!by.has(root)) by.set(root, []);
        by.get(root).push(i);
      });
      return [...by.values()].filter((g) => g.length > 1);
    }

    /** The robots drawn on the canvas (within ``margin`` pixels of it), in id order. */
    inView(margin = 0) {
      const w = this.canvas.width, h = this.canvas.height, out = [];
      for (let i = 0; i < this.rec.R; i++) {
        const [x, y] = this.canvasXY(i);
        if (x >= -margin && y >= -margin && x <= w + margin && y <= h + margin) out.push(i);
      }
      return out;
    }

    /** A cluster of overlapping robots: a ring around them, their count in a badge and their ids (as
     *  ranges: "0-15") in a label beside it, so a team spawned together stays readable. */
    drawCluster(members, ids) {
      const ctx = this.ctx, pts = members.map((i) => this.canvasXY(i));
      const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
      const cx = (Math.min(...xs) + Math.max(...xs)) / 2, cy = (Math.min(...ys) + Math.max(...ys)) / 2;
      const radius = Math.max(...pts.map(([x, y]) => Math.hypot(x - cx, y - cy))) + this.robotPx + 3;
      ctx.save();
      ctx.lineWidth = 1.5; ctx.strokeStyle = '#111'; ctx.setLineDash([3, 2]);
      ctx.beginPath(); ctx.arc(cx, cy, radius, 0, 2 * Math.PI); ctx.stroke(); ctx.setLineDash([]);
      ctx.font = `bold ${ID_FONT_PX}px sans-serif`;
      const badge = String(members.length), bw = Math.max(18, ctx.measureText(badge).width + 8);
      const bx = cx + (radius + bw / 2) * 0.71, by = cy - (radius + bw / 2) * 0.71;   // outside the ring
      ctx.fillStyle = '#111'; ctx.beginPath(); ctx.arc(bx, by, bw / 2, 0, 2 * Math.PI); ctx.fill();
      ctx.fillStyle = '#fff'; ctx.textAlign = 'center'; ctx.textBaseline = 'middle'; ctx.fillText(badge, bx, by + 0.5);
      if (ids) {   // beside the badge, or left of the ring where the canvas ends
        const text = `robots ${idRanges(members)}`, tw = ctx.measureText(text).width;
        const right = bx + bw / 2 + 3 + tw <= this.canvas.width;
        ctx.textAlign = 'left';
        this.haloText(text, right ? bx + bw / 2 + 3 : Math.max(2, cx - radius - 4 - tw), by, '#111');
      }
      ctx.restore();
    }

    /** Text with a white halo, readable over walls, trails and links. */
    haloText(text, x, y, colour) {
      const ctx = this.ctx;
      ctx.save();
      ctx.lineWidth = 3; ctx.strokeStyle = 'rgba(255,255,255,0.9)'; ctx.lineJoin = 'round';
      ctx.strokeText(text, x, y);
      ctx.fillStyle = colour; ctx.fillText(text, x, y);
      ctx.restore();
    }

    /** The goal every robot in view drives to (its latest navigate action's goal): a dashed line in its colour and a
     *  cross at the goal. The selected robot's goal is drawn again, in black, by drawDebug. */
    drawGoals() {
      const ctx = this.ctx, wMax = this.rec.W * this.cellM, hMax = this.rec.H * this.cellM;
      ctx.save();
      for (const i of this.inView(this.robotPx)) {   // robots in view (disc mode: at most POINTS_ABOVE)
        const goal = this.currentGoal(i, this.tick);
        if (!goal || goal[0] < 0 || goal[1] < 0 || goal[0] > wMax || goal[1] > hMax) continue;
        const [gx, gy] = this.worldToCanvas(goal[0], goal[1]), [x, y] = this.canvasXY(i);
        const colour = this.colour(i);
        ctx.strokeStyle = rgb(colour, 0.75); ctx.lineWidth = 1.5; ctx.setLineDash([3, 3]);
        ctx.beginPath(); ctx.moveTo(x, y); ctx.lineTo(gx, gy); ctx.stroke();
        ctx.setLineDash([]); ctx.lineWidth = 2.5; ctx.strokeStyle = rgb(colour);
        ctx.beginPath(); ctx.moveTo(gx - 4, gy - 4); ctx.lineTo(gx + 4, gy + 4);
        ctx.moveTo(gx + 4, gy - 4); ctx.lineTo(gx - 4, gy + 4); ctx.stroke();
        this.drawn.goals.push({ robot: i, goal: goal.slice(), x: gx, y: gy });
      }
      ctx.restore();
    }

    /** Metres per grid step / scale bar: the smallest NICE_METRES step at least ``minPx`` pixels long. */
    niceMetres(minPx) {
      const pxPerM = this.cellPx * this.zoom / this.cellM;
      return NICE_METRES.find((m) => m * pxPerM >= minPx) || NICE_METRES[NICE_METRES.length - 1];
    }

    /** A metre grid: faint lines every niceMetres(70) m from the map's origin (its south-west corner), labelled
     *  along the top and left edges in metres. */
    drawGrid() {
      const ctx = this.ctx, step = this.niceMetres(70), w = this.canvas.width, h = this.canvas.height;
      this.drawn.grid = step;
      const wM = this.rec.W * this.cellM, hM = this.rec.H * this.cellM;
      ctx.save();
      ctx.strokeStyle = 'rgba(0,0,0,0.13)'; ctx.lineWidth = 1;
      ctx.font = '11px sans-serif'; ctx.textBaseline = 'top';
      for (let m = 0; m <= wM + 1e-9; m += step) {
        const [x] = this.worldToCanvas(m, 0);
        if (x < -1 || x > w + 1) continue;
        ctx.beginPath(); ctx.moveTo(Math.round(x) + 0.5, 0); ctx.lineTo(Math.round(x) + 0.5, h); ctx.stroke();
        if (m > 0) this.haloText(`${+m.toFixed(1)}`, x + 2, 2, '#333');
      }
      for (let m = 0; m <= hM + 1e-9; m += step) {
        const [, y] = this.worldToCanvas(0, m);
        if (y < -1 || y > h + 1) continue;
        ctx.beginPath(); ctx.moveTo(0, Math.round(y) + 0.5); ctx.lineTo(w, Math.round(y) + 0.5); ctx.stroke();
        if (m > 0 && y > 14) this.haloText(`${+m.toFixed(1)} m`, 2, y + 2, '#333');
      }
      ctx.restore();
    }

    /** A scale bar in the bottom-left corner: niceMetres(80) m, on a white plate. */
    drawScaleBar() {
      const ctx = this.ctx, metres = this.niceMetres(80);
      const px = metres / this.cellM * this.cellPx * this.zoom, x = 12, y = this.canvas.height - 14;
      ctx.save();
      ctx.fillStyle = 'rgba(255,255,255,0.85)'; ctx.fillRect(x - 6, y - 22, px + 12, 30);
      ctx.fillStyle = '#000'; ctx.fillRect(x, y - 3, px, 6);
      ctx.fillRect(x, y - 8, 2, 12); ctx.fillRect(x + px - 2, y - 8, 2, 12);
      ctx.font = 'bold 12px sans-serif'; ctx.textAlign = 'center'; ctx.textBaseline = 'bottom';
      ctx.fillText(`${metres} m`, x + px / 2, y - 7);
      ctx.restore();
      this.drawn.scale = { metres, px, x, y };
    }

    /** Robot i as a disc of radius r in its colour with a heading tick (and its number). */
    drawDisc(i, r, label) {
      const ctx = this.ctx;
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
      if (label) this.haloText(String(i), cx + r + 2, cy - r - 1, '#000');
    }

    /** Many robots: a square point per robot, at most one per POINT_CELL x POINT_CELL pixel square (the
     *  lowest-numbered robot in it), one fill per colour; so a frame costs O(R) arithmetic and at most one
     *  draw per screen cell however the swarm crowds. The selected robot is a disc on top. */
    drawPoints() {
      const ctx = this.ctx, R = this.rec.R, cell = POINT_CELL;
      const gw = Math.ceil(this.canvas.width / cell), gh = Math.ceil(this.canvas.height / cell);
      if (!this.pointGrid || this.pointGrid.length !== gw * gh) this.pointGrid = new Uint8Array(gw * gh);
      const taken = this.pointGrid.fill(0);
      const paths = new Map();
      const p = this.rec.poses, cellM = this.cellM, cellPx = this.cellPx, H = this.rec.H;
      const zoom = this.zoom, offX = this.offX, offY = this.offY;
      let drawn = 0;
      for (let i = 0, k = this.tick * R * 3; i < R; i++, k += 3) {
        const cx = p[k] / cellM * cellPx * zoom - offX, cy = (H - p[k + 1] / cellM) * cellPx * zoom - offY;   // canvasXY
        const gx = Math.floor(cx / cell), gy = Math.floor(cy / cell);
        if (gx < 0 || gy < 0 || gx >= gw || gy >= gh || taken[gy * gw + gx]) continue;
        taken[gy * gw + gx] = 1;
        const c = i % this.robotColours.length;
        if (!paths.has(c)) paths.set(c, new Path2D());
        paths.get(c).rect(cx - cell / 2, cy - cell / 2, cell, cell);
        drawn++;
      }
      for (const [c, path] of paths) { ctx.fillStyle = rgb(this.robotColours[c]); ctx.fill(path); }
      this.drawn.robots = drawn;
      if (this.selectedRobot !== null) this.drawDisc(this.selectedRobot, 4, false);
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

    linkCount() { return this.state.links; }

    updateReadout() {
      const t = this.tick, off = this.rec.off.msg;
      document.getElementById('readout').textContent =
        `tick ${t} / ${this.rec.T - 1} (${(t * this.head.tick_s).toFixed(1)} s) · explored ` +
        `${(100 * this.rec.explored[t]).toFixed(1)} % · coverage ${(100 * this.rec.coverage[t]).toFixed(1)} % · ` +
        `${this.linkCount()} links · ${off[t + 1] - off[t]} messages sent this tick` +
        (this.rec.hasComm
          ? ` · lost in the last ${LOST_TICKS} ticks: ${this.lostCount(t)} · ${plural(this.groups().length, 'group')}`
          : '');
    }

    /** Deliveries lost in the window the lost-message layer draws: ticks t - LOST_TICKS + 1 to t. */
    lostCount(t) {
      const m = this.rec.msg, off = this.rec.off.msg;
      return m.lostOff[off[t + 1]] - m.lostOff[off[Math.max(0, t - LOST_TICKS + 1)]];
    }

    updatePanel(i) {
      const R = this.rec.R, t = this.tick;
      const free = this.state.counts[3 * i + FREE], solid = this.state.counts[3 * i + SOLID];
      const { sent, bytes, received } = this.messageTotals(i, t);
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
      for (let s = 0; s < R; s++) if (s !== i && this.state.linked(i, s)) heard.push(s);
      const many = heard.length > LIST_ITEMS;
      if (many) heard.sort((a, b) => this.margin(i, b) - this.margin(i, a) || a - b);   // the strongest first
      document.getElementById('robot-links').textContent = heard.length
        ? listed(heard.map((s) => `${s} (${fmt(this.margin(i, s), 1)} dB margin)`),
                 many ? ` (the strongest ${LIST_ITEMS} of ${heard.length})` : '') : 'nobody';
      document.getElementById('robot-debug').textContent =
        act && act.debug !== null && act.debug !== undefined ? JSON.stringify(act.debug, null, 1) : '(none)';
    }

    /** When robot i last merged (a map holding) each robot's map, at tick t: its entries in the map-merge
     *  stream up to t (kept up to PAIR_AGES_UP_TO robots, where they are few). */
    mergedRow(i, t) {
      const R = this.rec.R, a = this.rec.aoi, row = new Float64Array(R);
      for (let k = 0; k < this.rec.off.aoi[t + 1]; k++) {
        if (a.idx[k] >= i * R && a.idx[k] < (i + 1) * R) row[a.idx[k] - i * R] = a.val[k];
      }
      return row;
    }

    /** The robot panel's communication rows: its group, last contact, and how old its information about
     *  each other robot is (that list at team size only, see PAIR_AGES_UP_TO). */
    commFacts(i) {
      const R = this.rec.R, t = this.tick, tickS = this.head.tick_s, c = this.commState()[i];
      const mates = this.groups().find((g) => g.includes(i)).filter((j) => j !== i);
      let ages = [];
      if (this.rec.aoi) {
        const merged = this.mergedRow(i, t), others = [];
        for (let s = 0; s < R; s++) if (s !== i) others.push(s);
        if (others.length > LIST_ITEMS) others.sort((a, b) => merged[a] - merged[b] || a - b);
        ages = others.map((s) => `${s}: ${((t - merged[s]) * tickS).toFixed(1)} s`);
      }
      return [['group', mates.length ? `with ${listed(mates.map(String), mates.length > LIST_ITEMS ? ` (${mates.length})` : '')}` : 'alone'],
              ['last contact', `${(c.since * tickS).toFixed(1)} s ago`],
              ['missing', `${(100 * c.missing).toFixed(1)} % of the team's free cells`],
              ['info age', `${(c.age * tickS).toFixed(1)} s on average` + (ages.length ? '; ' +
                listed(ages, ages.length > LIST_ITEMS ? ` (the oldest ${LIST_ITEMS} of ${ages.length})` : '') : '')]];
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
      items.push('<span><b>&times;</b> goal, dashed from its robot</span>',
                 '<span><span class="badge">n</span> n robots drawn on top of each other</span>',
                 '<span>grid and scale bar in metres</span>');
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
        knownCell: (i, row, col) => v.robotMap(i).map[row * v.rec.W + col],
        pointMode: () => v.points,
        // zoom about the canvas point (cx, cy) by factor (as the mouse wheel), or read the view
        zoomAt: (factor, cx, cy) => { v.zoomAt(factor, cx, cy); v.draw(); },
        view: () => ({ zoom: v.zoom, offX: v.offX, offY: v.offY }),
        profile: () => ({ ...v.profile }),
        drawnCounts: () => ({ robots: v.drawn.robots, links: v.drawn.links, messages: v.drawn.messages,
                              losses: v.drawn.losses.length }),
        budgets: { pointCell: POINT_CELL, links: LINK_BUDGET, messages: MESSAGE_BUDGET, losses: LOSS_BUDGET,
                   aoiRows: AOI_ROWS, listItems: LIST_ITEMS },
        // bytes of the replay state (with its keyframes) and of the robot maps built for the selected robot
        stateBytes: () => ({ state: v.state.bytes(), robotMaps: v.robotMaps.reduce((n, m) => n + m.bytes(), 0),
                             robotMapCount: v.robotMaps.length }),
        seenCell: (row, col) => v.state.seen[row * v.rec.W + col],
        hasComm: v.rec.hasComm,
        groups: () => v.groups(),
        aoi: () => v.commState(),
        drawnLosses: () => v.drawn.losses.map((d) => ({ ...d })),
        drawnGroups: () => v.drawn.groups.map((g) => ({ members: g.members.slice(), colour: g.colour.slice(),
                                                        hull: g.hull.map((p) => p.slice()) })),
        causeColour: (cause) => causeColour(cause).slice(),
        trailRange: () => v.trailRange.slice(),
        lostTicks: LOST_TICKS,
        lostCount: () => v.lostCount(v.tick),
        drawnGoals: () => v.drawn.goals.map((g) => ({ ...g, goal: g.goal.slice() })),
        currentGoal: (i) => v.currentGoal(i, v.tick),
        drawnClusters: () => v.drawn.clusters.map((c) => c.slice()),
        scaleBar: () => (v.drawn.scale ? { ...v.drawn.scale } : null),
        cellPx: () => v.cellPx,
        gridMetres: () => v.drawn.grid,
        tooltipAt: (cx, cy) => { v.showTip(cx, cy, 0, 0); return v.tip.hidden ? '' : v.tip.textContent; },
      };
    }
  }

  async function main() {
    const status = document.getElementById('status');
    try {
      const cfg = JSON.parse(document.getElementById('swr-config').textContent);
      const bytes = embeddedBytes([...document.querySelectorAll('script.swr-data')]);
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
