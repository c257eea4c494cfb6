#include "app/sweep/report_html.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <vector>

namespace hgrasp::app::sweep {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The page's style. System fonts only: the page names no font file.
constexpr const char* kStyle = R"CSS(
:root { --fg: #1c2330; --muted: #5d6675; --line: #d8dde5; --bg: #f5f6f8; --card: #fff;
  --accent: #2f6db5; --ok: #1f7a3a; --bad: #b3261e; }
* { box-sizing: border-box; }
body { margin: 0; padding: 16px 24px 40px; background: var(--bg); color: var(--fg);
  font: 13px/1.4 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; }
h1 { font-size: 20px; margin: 0 0 2px; }
h2 { font-size: 15px; margin: 22px 0 8px; }
.muted, .meta { color: var(--muted); }
.meta strong { color: var(--fg); }
#errors { background: #fff0f0; color: var(--bad); border: 1px solid #e8b4b0; padding: 8px;
  white-space: pre-wrap; }
#errors:empty { display: none; }
.cards { display: flex; flex-wrap: wrap; gap: 10px; margin-top: 12px; }
.card { background: var(--card); border: 1px solid var(--line); border-radius: 6px;
  padding: 8px 12px; min-width: 130px; }
.card .v { font-size: 20px; font-weight: 600; font-variant-numeric: tabular-nums; }
.card .k { color: var(--muted); font-size: 12px; }
.card.good .v { color: var(--ok); }
.card.bad .v { color: var(--bad); }
.chip { display: inline-block; margin: 3px 4px 0 0; padding: 0 6px; border-radius: 9px;
  background: #f3d9d7; color: #7a1d17; cursor: pointer; font-size: 12px; }
#plots { display: grid; grid-template-columns: repeat(auto-fill, minmax(370px, 1fr)); gap: 10px; }
.plot { margin: 0; background: var(--card); border: 1px solid var(--line); border-radius: 6px;
  padding: 6px 8px; }
.plot figcaption { font-size: 12px; }
.plot .stats { color: var(--muted); font-variant-numeric: tabular-nums; }
.plot .empty { color: var(--muted); margin: 8px 0; }
.plot svg { display: block; width: 100%; height: auto; }
svg text { font-size: 10px; fill: #333; }
svg .axis { stroke: #777; stroke-width: 1; }
svg .grid { stroke: #e6e9ee; stroke-width: 1; }
svg .bar { fill: #6a9bd1; }
svg .bar.over { fill: #d9893b; }
svg line.med { stroke: #1c2330; stroke-width: 1.5; stroke-dasharray: 4 3; }
svg line.p95 { stroke: #c62828; stroke-width: 1.5; stroke-dasharray: 4 3; }
svg text.med { fill: #1c2330; font-weight: 600; }
svg text.p95 { fill: #c62828; font-weight: 600; }
.toolbar { display: flex; gap: 14px; align-items: center; margin-bottom: 6px; }
.toolbar input[type=search] { width: 260px; padding: 3px 6px; }
table.scenes { border-collapse: collapse; width: 100%; background: var(--card);
  font-variant-numeric: tabular-nums; }
table.scenes th, table.scenes td { border-bottom: 1px solid var(--line); padding: 3px 6px;
  text-align: right; white-space: nowrap; }
table.scenes th { position: sticky; top: 0; background: #e9edf3; cursor: pointer;
  user-select: none; z-index: 1; white-space: normal; vertical-align: bottom; }
table.scenes th.sorted-desc::after { content: " \25BC"; font-size: 9px; }
table.scenes th.sorted-asc::after { content: " \25B2"; font-size: 9px; }
table.scenes th.text, table.scenes td.text { text-align: left; }
tr.scene { cursor: pointer; }
tr.scene:hover td { background: #eef3fb; }
tr.scene td.name::before { content: "\25B8  "; color: var(--muted); }
tr.scene.open td.name::before { content: "\25BE  "; }
tr.scene.bad td { background: #fbe3e1; }
tr.scene.bad:hover td { background: #f6d0cc; }
tr.scene.st-crash td { background: #f4c7c3; }
tr.scene.st-timeout td { background: #fbe7cf; }
tr.scene.st-bad_input td, tr.scene.st-error td { background: #ece1f5; }
td.status { text-align: left; font-weight: 600; }
tr.scene.st-ok td.status { color: var(--ok); }
tr.scene.bad td.status { color: var(--bad); }
td.warn { color: var(--bad); font-weight: 600; }
tr.detail > td { background: #fafbfc; text-align: left; white-space: normal; padding: 8px 12px 12px; }
.facts { display: flex; flex-wrap: wrap; gap: 4px 16px; margin-bottom: 6px; }
.kv .k { color: var(--muted); }
pre.why { background: #fff0f0; border: 1px solid #e8b4b0; padding: 6px; margin: 4px 0;
  white-space: pre-wrap; max-width: 1100px; }
table.boxes { border-collapse: collapse; margin: 6px 0; }
table.boxes th, table.boxes td { border: 1px solid var(--line); padding: 1px 6px; text-align: right; }
table.boxes th { background: #f0f2f5; }
.thumbs { display: flex; flex-wrap: wrap; gap: 8px; margin-top: 6px; }
.thumb { margin: 0; text-align: center; font-size: 11px; color: var(--muted); }
.thumb img { display: block; width: 160px; border: 1px solid var(--line); }
.legend span { display: inline-block; padding: 0 6px; margin-right: 4px; border-radius: 3px; }
)CSS";

// Registered before the main script, so that even a syntax error in it is reported on the page.
constexpr const char* kErrorHandler = R"JS(
window.onerror = function (message, source, line, column) {
  var el = document.getElementById('errors');
  if (el) el.textContent += 'error: ' + message + (line ? ' (line ' + line + ':' + column + ')' : '') + '\n';
};
)JS";

// The page's script: reads the data blob and draws everything. Each part is drawn in its own
// try/catch, so that a bad field breaks one part, says so in #errors, and leaves the rest.
constexpr const char* kScript = R"JS(
(function () {
'use strict';
const DASH = '\u2013';
const $ = (id) => document.getElementById(id);

function report(where, e) {
  $('errors').textContent += where + ': ' + (e && e.stack ? e.stack : String(e)) + '\n';
}
function isNum(x) { return typeof x === 'number' && isFinite(x); }
function obj(x) { return x !== null && typeof x === 'object' && !Array.isArray(x) ? x : {}; }
function list(x) { return Array.isArray(x) ? x : (x === null || x === undefined ? [] : [x]); }
const ESC = {'&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;'};
function esc(x) { return String(x).replace(/[&<>"']/g, (c) => ESC[c]); }
// A number for people: integers whole, others to a precision that suits their size.
function fmt(x) {
  if (!isNum(x)) return DASH;
  if (Number.isInteger(x)) return String(x);
  const a = Math.abs(x);
  if (a >= 1000) return x.toFixed(0);
  if (a >= 100) return x.toFixed(1);
  if (a >= 1) return x.toFixed(2);
  if (a >= 0.01) return x.toFixed(3);
  return x.toPrecision(2);
}
// Any field as text: "–" for null/missing.
function show(x) {
  if (x === null || x === undefined || x === '') return DASH;
  if (typeof x === 'number') return fmt(x);
  if (typeof x === 'boolean') return x ? 'yes' : 'no';
  if (Array.isArray(x)) return x.map(show).join(', ');
  if (typeof x === 'object') return JSON.stringify(x);
  return String(x);
}
function maxOf(xs) {
  let m = null;
  for (const x of xs) if (isNum(x) && (m === null || x > m)) m = x;
  return m;
}
function abs(x) { return isNum(x) ? Math.abs(x) : null; }
function ratio(a, b) { return isNum(a) && isNum(b) && b > 0 ? ' (' + (100 * a / b).toFixed(0) + '%)' : ''; }
// A relative path as a URL: each part percent-encoded ('#', '?', '%' and spaces are legal in names).
function href(path) { return String(path).split('/').map(encodeURIComponent).join('/'); }

let data = {};
try { data = obj(JSON.parse($('data').textContent)); } catch (e) { report('data', e); }
const summary = obj(data.summary);
const scenes = list(summary.scenes).map(obj);
const thumbs = list(data.thumbs);

const boxesOf = (s) => list(s.boxes).filter((b) => b !== null && typeof b === 'object');
function statusOf(s) {
  if (typeof s.status === 'string' && s.status !== '') return s.status;
  return s.ok === true ? 'ok' : 'unknown';
}
function statusText(s) {
  const st = statusOf(s);
  let t = st;
  if (s.failure !== null && s.failure !== undefined && s.failure !== '' && s.failure !== st)
    t += ': ' + s.failure;
  if (isNum(s.signal)) t += ' (signal ' + s.signal + ')';
  else if (st !== 'ok' && isNum(s.exit_code) && s.exit_code !== 0) t += ' (exit ' + s.exit_code + ')';
  return t;
}

// ---- header -------------------------------------------------------------------------------
function renderHeader() {
  const sw = obj(summary.sweep), t = obj(summary.totals);
  const n = isNum(t.scenes) ? t.scenes : isNum(sw.scenes) ? sw.scenes : scenes.length;
  document.title = 'hgrasp sweep: ' + show(sw.stage) + ', ' + n + ' scenes, ' + show(sw.started_utc);
  $('title').textContent = 'hgrasp sweep \u2013 ' + show(sw.stage);
  $('meta').innerHTML = [
    ['stage', show(sw.stage)],
    ['devices', sw.lockstep ? 'real drivers, twin in lockstep' : 'simulated'],
    ['scenes', show(n)], ['started', show(sw.started_utc)],
    ['jobs', show(sw.jobs)], ['time limit s', show(sw.time_limit_s)],
    ['sweep wall s', show(t.sweep_wall_s)], ['scene wall s (sum)', show(t.wall_s)],
  ].map(([k, v]) => esc(k) + ' <strong>' + esc(v) + '</strong>').join(' &middot; ');

  const failures = obj(t.failures);
  const chips = Object.keys(failures).sort((a, b) => (failures[b] || 0) - (failures[a] || 0))
    .map((k) => '<span class="chip" data-filter="' + esc(k) + '" title="show only these">' +
      esc(k) + ' ' + esc(show(failures[k])) + '</span>').join('');
  const card = (cls, k, v, extra) => '<div class="card ' + cls + '"><div class="v">' + esc(v) +
    '</div><div class="k">' + esc(k) + '</div>' + (extra || '') + '</div>';
  $('cards').innerHTML = [
    card(isNum(t.ok) && t.ok === n ? 'good' : '', 'ok', show(t.ok) + ' / ' + show(n) + ratio(t.ok, n)),
    card(isNum(t.failed) && t.failed > 0 ? 'bad' : '', 'failed', show(t.failed), chips),
    card('', 'boxes found', show(t.boxes_found) + ' / ' + show(t.boxes) + ratio(t.boxes_found, t.boxes)),
    card('', 'boxes within tolerance', show(t.boxes_within_tolerance) + ' / ' + show(t.boxes) +
      ratio(t.boxes_within_tolerance, t.boxes)),
    card('', 'lifted', show(t.lifted) + ' / ' + show(n) + ratio(t.lifted, n)),
    card('', 'scenes per hour', show(t.scenes_per_hour)),
  ].join('');
  for (const chip of document.querySelectorAll('.chip[data-filter]')) {
    chip.addEventListener('click', () => { $('filter').value = chip.dataset.filter; applyFilter(); });
  }
}

// ---- histograms ---------------------------------------------------------------------------
const FIGURES = [
  {id: 'center_mm', title: 'Box centre error', unit: 'mm', per: 'boxes',
   of: (s) => boxesOf(s).map((b) => b.center_mm)},
  {id: 'max_edge_mm', title: 'Box max edge error', unit: 'mm', per: 'boxes',
   of: (s) => boxesOf(s).map((b) => b.max_edge_mm)},
  {id: 'yaw_deg', title: 'Box yaw error, absolute', unit: 'deg', per: 'boxes',
   of: (s) => boxesOf(s).map((b) => abs(b.yaw_deg))},
  {id: 'range_rms_mm', title: 'Range RMS error', unit: 'mm', per: 'scenes',
   of: (s) => [obj(s.range).rms_mm]},
  {id: 'coverage', title: 'Range coverage', unit: 'fraction', per: 'scenes',
   of: (s) => [obj(s.range).coverage]},
  {id: 'outlier_fraction', title: 'Range outlier fraction', unit: 'fraction', per: 'scenes',
   of: (s) => [obj(s.range).outlier_fraction]},
  {id: 'contact_mm', title: 'Grasp contact distance', unit: 'mm', per: 'contacts',
   of: (s) => list(obj(s.grasp).contact_mm)},
  {id: 'servo_mm', title: 'Servo final gripper-to-plan', unit: 'mm', per: 'scenes',
   of: (s) => [obj(s.servo).gripper_to_plan_mm]},
  {id: 'servo_deg', title: 'Servo final gripper-to-plan', unit: 'deg', per: 'scenes',
   of: (s) => [obj(s.servo).gripper_to_plan_deg]},
  {id: 'true_rise_mm', title: 'True rise of the box', unit: 'mm', per: 'scenes',
   of: (s) => [obj(s.lift).true_rise_mm]},
  {id: 'wall_s', title: 'Wall time per scene', unit: 's', per: 'scenes', of: (s) => [s.wall_s]},
];

// Linear interpolation between order statistics (sorted ascending, not empty).
function quantile(sorted, p) {
  const h = (sorted.length - 1) * p, i = Math.floor(h);
  return i + 1 < sorted.length ? sorted[i] + (h - i) * (sorted[i + 1] - sorted[i]) : sorted[i];
}
// A step of 1, 2, 2.5 or 5 times a power of ten that splits `span` into about `count` parts.
function niceStep(span, count) {
  const raw = span / Math.max(1, count);
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / mag;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 2.5 ? 2.5 : f <= 5 ? 5 : 10) * mag;
}
function decimalsOf(step) {
  for (let d = 0; d < 8; ++d) if (Math.abs(step * Math.pow(10, d) - Math.round(step * Math.pow(10, d))) < 1e-6) return d;
  return 8;
}

// The histogram of `sorted` (finite numbers, ascending, not empty) as an SVG string. With 20
// values or more, a long tail (beyond Tukey's outer fence, q3 + 3 IQR, and the 95th percentile)
// goes into one overflow bar on the right, so that a few gross errors cannot squeeze the bulk
// into a bin or two.
function histogramSvg(fig, sorted) {
  const n = sorted.length;
  const med = quantile(sorted, 0.5), p95 = quantile(sorted, 0.95);
  const q1 = quantile(sorted, 0.25), q3 = quantile(sorted, 0.75);
  let lo = sorted[0], hi = sorted[n - 1];
  const cap = Math.max(q3 + 3 * (q3 - q1), p95);
  if (n >= 20 && cap > lo && hi - lo > 1.5 * (cap - lo)) hi = cap;
  const overflow = sorted.filter((x) => x > hi).length;
  if (hi <= lo) { const pad = Math.abs(lo) * 0.05 || 0.5; lo -= pad; hi += pad; }
  const step = niceStep(hi - lo, Math.min(30, Math.max(6, Math.ceil(Math.sqrt(n)))));
  const x0 = Math.floor(lo / step + 1e-9) * step;
  const bins = Math.max(1, Math.ceil((hi - x0) / step - 1e-9));
  const x1 = x0 + bins * step;
  const counts = new Array(bins).fill(0);
  for (const x of sorted) if (x <= hi) counts[Math.min(bins - 1, Math.max(0, Math.floor((x - x0) / step)))]++;

  const W = 380, H = 215, ml = 40, mr = 12, mt = 30, mb = 38;
  const ovW = overflow ? 34 : 0;
  const pw = W - ml - mr - ovW, ph = H - mt - mb;
  const X = (x) => ml + (x - x0) / (x1 - x0) * pw;
  const cmax = Math.max(overflow, ...counts);
  const ys = Math.max(1, Math.ceil(niceStep(cmax, 4)));
  const ymax = Math.max(ys, Math.ceil(cmax / ys) * ys);
  const Y = (c) => mt + ph - c / ymax * ph;
  const p = [];
  p.push('<svg viewBox="0 0 ' + W + ' ' + H + '" role="img" aria-label="' + esc(fig.title) + '">');
  for (let c = 0; c <= ymax; c += ys) {
    p.push('<line class="grid" x1="' + ml + '" x2="' + (ml + pw) + '" y1="' + Y(c) + '" y2="' + Y(c) + '"/>');
    p.push('<text x="' + (ml - 4) + '" y="' + (Y(c) + 3) + '" text-anchor="end">' + c + '</text>');
  }
  const bw = pw / bins;
  counts.forEach((c, i) => {
    if (!c) return;
    const a = x0 + i * step;
    p.push('<rect class="bar" x="' + (X(a) + 0.5) + '" y="' + Y(c) + '" width="' + Math.max(1, bw - 1) +
      '" height="' + (Y(0) - Y(c)) + '"><title>' + fmt(a) + ' to ' + fmt(a + step) + ' ' + esc(fig.unit) +
      ': ' + c + '</title></rect>');
  });
  if (overflow) {
    const ox = ml + pw + 8;
    p.push('<rect class="bar over" x="' + ox + '" y="' + Y(overflow) + '" width="' + (ovW - 10) +
      '" height="' + (Y(0) - Y(overflow)) + '"><title>above ' + fmt(hi) + ' ' + esc(fig.unit) + ': ' +
      overflow + ' (max ' + fmt(sorted[n - 1]) + ')</title></rect>');
    p.push('<text x="' + (ox + (ovW - 10) / 2) + '" y="' + (Y(0) + 12) + '" text-anchor="middle">&gt;' + fmt(hi) + '</text>');
  }
  p.push('<line class="axis" x1="' + ml + '" x2="' + (ml + pw) + '" y1="' + Y(0) + '" y2="' + Y(0) + '"/>');
  p.push('<line class="axis" x1="' + ml + '" x2="' + ml + '" y1="' + mt + '" y2="' + Y(0) + '"/>');
  const ts = niceStep(x1 - x0, 5), td = decimalsOf(ts);
  for (let k = Math.ceil(x0 / ts - 1e-9); k * ts <= x1 + 1e-9 * ts; ++k) {
    const x = X(k * ts);
    p.push('<line class="axis" x1="' + x + '" x2="' + x + '" y1="' + Y(0) + '" y2="' + (Y(0) + 4) + '"/>');
    p.push('<text x="' + x + '" y="' + (Y(0) + 14) + '" text-anchor="middle">' + (k * ts).toFixed(td) + '</text>');
  }
  p.push('<text x="' + (ml + pw / 2) + '" y="' + (H - 4) + '" text-anchor="middle">' +
    esc(fig.title + ' (' + fig.unit + ')') + '</text>');
  p.push('<text transform="translate(10 ' + (mt + ph / 2) + ') rotate(-90)" text-anchor="middle">count (' +
    esc(fig.per) + ')</text>');
  // The two markers, their values written above the plot on two lines so they never overlap.
  [['med', med, 'median ', mt - 17], ['p95', p95, 'p95 ', mt - 5]].forEach(([cls, v, label, ty]) => {
    const x = X(v);
    const anchor = x > ml + pw * 0.6 ? 'end' : 'start';
    p.push('<line class="' + cls + '" x1="' + x + '" x2="' + x + '" y1="' + (mt - 2) + '" y2="' + Y(0) + '"/>');
    p.push('<text class="' + cls + '" x="' + (anchor === 'end' ? x - 3 : x + 3) + '" y="' + ty +
      '" text-anchor="' + anchor + '">' + label + fmt(v) + '</text>');
  });
  p.push('</svg>');
  return p.join('');
}

function renderPlots() {
  const parts = [];
  for (const fig of FIGURES) {
    try {
      const v = [];
      for (const s of scenes) for (const x of fig.of(s)) if (isNum(x)) v.push(x);
      v.sort((a, b) => a - b);
      let stats = '', body;
      if (v.length) {
        stats = 'n ' + v.length + ' ' + fig.per + ' &middot; min ' + fmt(v[0]) + ' &middot; median ' +
          fmt(quantile(v, 0.5)) + ' &middot; p95 ' + fmt(quantile(v, 0.95)) + ' &middot; max ' + fmt(v[v.length - 1]);
        body = histogramSvg(fig, v);
      } else {
        body = '<p class="empty">no values: no scene has this figure</p>';
      }
      parts.push('<figure class="plot" data-figure="' + fig.id + '"><figcaption><strong>' + esc(fig.title) +
        '</strong> (' + esc(fig.unit) + ') <span class="stats">' + stats + '</span></figcaption>' + body + '</figure>');
    } catch (e) {
      report('plot ' + fig.id, e);
    }
  }
  $('plots').innerHTML = parts.join('');
}

// ---- table ----------------------------------------------------------------------------------
// val: the value sorted by (null sorts last either way); text: the cell; first: the direction of
// a first click (worst first where "worst" is clear).
const COLUMNS = [
  {key: 'scene', label: 'scene', cls: 'text name', first: 1, val: (s) => s.scene === undefined ? null : String(s.scene)},
  {key: 'status', label: 'status / failure', cls: 'text status', first: 1, val: (s) => statusText(s)},
  {key: 'boxes', label: 'boxes found', first: 1, title: 'boxes found / in the scene',
   val: (s) => isNum(s.boxes_found) && isNum(s.boxes_total) ? s.boxes_found - s.boxes_total : null,
   text: (s) => s.boxes_found == null && s.boxes_total == null ? DASH : show(s.boxes_found) + '/' + show(s.boxes_total),
   warn: (s) => isNum(s.boxes_found) && isNum(s.boxes_total) && s.boxes_found < s.boxes_total},
  {key: 'centre', label: 'worst centre mm', first: -1, val: (s) => maxOf(boxesOf(s).map((b) => b.center_mm)),
   warn: (s) => boxesOf(s).some((b) => b.found === true && b.within_tolerance === false)},
  {key: 'edge', label: 'worst edge mm', first: -1, val: (s) => maxOf(boxesOf(s).map((b) => b.max_edge_mm))},
  {key: 'yaw', label: 'worst yaw deg', first: -1, val: (s) => maxOf(boxesOf(s).map((b) => abs(b.yaw_deg)))},
  {key: 'rms', label: 'range RMS mm', first: -1, val: (s) => obj(s.range).rms_mm},
  {key: 'coverage', label: 'coverage', first: 1, val: (s) => obj(s.range).coverage},
  {key: 'contact', label: 'contact mm', first: -1, title: 'largest grasp contact distance',
   val: (s) => maxOf(list(obj(s.grasp).contact_mm))},
  {key: 'servo', label: 'servo mm / deg', first: -1, title: 'final gripper-to-plan error',
   val: (s) => obj(s.servo).gripper_to_plan_mm,
   text: (s) => s.servo == null ? DASH : fmt(obj(s.servo).gripper_to_plan_mm) + ' / ' + fmt(obj(s.servo).gripper_to_plan_deg)},
  {key: 'rise', label: 'rise mm', first: 1, title: 'true rise of the box', val: (s) => obj(s.lift).true_rise_mm,
   warn: (s) => obj(s.lift).lifted === false},
  {key: 'wall', label: 'wall s', first: -1, val: (s) => s.wall_s},
  {key: 'score', label: 'score', first: -1, title: 'higher is worse', val: (s) => s.score},
];

let rows = [];
let sortKey = 'score', sortDir = -1;

function cellHtml(col, s) {
  const v = col.val(s);
  let cls = col.cls || '';
  try { if (col.warn && col.warn(s)) cls += ' warn'; } catch (e) { report('cell ' + col.key, e); }
  const text = col.text ? col.text(s) : (typeof v === 'string' ? v : fmt(v));
  cls = cls.trim();
  return (cls ? '<td class="' + cls + '">' : '<td>') + esc(text) + '</td>';
}

function kv(k, v) { return '<span class="kv"><span class="k">' + esc(k) + '</span> ' + esc(show(v)) + '</span>'; }

function detailHtml(s, pics) {
  const r = obj(s.range), h = obj(s.hoover), g = obj(s.grasp), sv = obj(s.servo), l = obj(s.lift);
  let out = '<div class="facts">' + kv('file', s.file) + kv('seed', s.seed) + kv('stage', s.stage) +
    kv('exit code', s.exit_code) + kv('signal', s.signal) + kv('wall s', s.wall_s) +
    kv('robot s', s.robot_s) + kv('target', s.target_object) + '</div>';
  if (s.failure_detail !== null && s.failure_detail !== undefined && s.failure_detail !== '')
    out += '<pre class="why">' + esc(show(s.failure_detail)) + '</pre>';
  out += '<div class="facts"><strong>range</strong>' + (s.range ? kv('points', r.points) + kv('RMS mm', r.rms_mm) +
    kv('outliers', r.outliers) + kv('outlier fraction', r.outlier_fraction) + kv('coverage', r.coverage) : DASH) + '</div>';
  out += '<div class="facts"><strong>segments</strong>' + (s.hoover ? kv('truth regions', h.truth_regions) +
    kv('correct', h.correct) + kv('over', h.over) + kv('under', h.under) + kv('missed', h.missed) +
    kv('noise', h.noise) : DASH) + '</div>';
  out += '<div class="facts"><strong>grasp</strong>' + (s.grasp ? kv('planned', g.planned) + kv('arm', g.arm) +
    kv('contact mm', g.contact_mm) : DASH) + ' <strong>servo</strong>' + (s.servo ? kv('mm', sv.gripper_to_plan_mm) +
    kv('deg', sv.gripper_to_plan_deg) : DASH) + ' <strong>lift</strong>' + (s.lift ? kv('lifted', l.lifted) +
    kv('true rise mm', l.true_rise_mm) : DASH) + '</div>';
  const boxes = boxesOf(s);
  if (boxes.length) {
    out += '<table class="boxes"><tr><th>object</th><th>found</th><th>box</th><th>centre mm</th><th>edges mm</th>' +
      '<th>max edge mm</th><th>yaw deg</th><th>colour</th><th>true colour</th><th>within tolerance</th></tr>';
    for (const b of boxes) {
      const bad = (x) => x === false ? ' class="warn"' : '';
      out += '<tr><td>' + esc(show(b.object)) + '</td><td' + bad(b.found) + '>' + esc(show(b.found)) + '</td><td>' +
        esc(show(b.box)) + '</td><td>' + esc(show(b.center_mm)) + '</td><td>' + esc(show(b.edge_mm)) + '</td><td>' +
        esc(show(b.max_edge_mm)) + '</td><td>' + esc(show(b.yaw_deg)) + '</td><td' + bad(b.color_ok) + '>' +
        esc(show(b.color_name)) + '</td><td>' + esc(show(b.true_color_name)) + '</td><td' + bad(b.within_tolerance) +
        '>' + esc(show(b.within_tolerance)) + '</td></tr>';
    }
    out += '</table>';
  }
  const ps = list(pics).filter((p) => p && typeof p.jpeg === 'string');
  if (ps.length) {
    // The base64 comes from the C++ (its alphabet needs no escaping); names and paths do.
    out += '<div class="thumbs">' + ps.map((p) => '<figure class="thumb"><a href="' + esc(href(p.href)) +
      '" target="_blank" title="' + esc(p.href) + '"><img alt="' + esc(p.name) + '" src="data:image/jpeg;base64,' +
      p.jpeg + '"></a><figcaption>' + esc(p.name) + '</figcaption></figure>').join('') + '</div>';
  } else {
    out += '<p class="muted">no pictures</p>';
  }
  return out;
}

function renderTable() {
  $('thead').innerHTML = '<tr>' + COLUMNS.map((c) => '<th data-key="' + c.key + '" class="' + (c.cls || '') +
    '"' + (c.title ? ' title="' + esc(c.title) + '"' : '') + '>' + esc(c.label) + '</th>').join('') + '</tr>';
  rows = scenes.map((s, i) => {
    const st = statusOf(s);
    const tr = document.createElement('tr');
    tr.className = 'scene st-' + st.replace(/[^A-Za-z0-9_]/g, '_') + (st === 'ok' ? '' : ' bad');
    tr.dataset.i = i;
    if (s.failure_detail !== null && s.failure_detail !== undefined) tr.title = show(s.failure_detail);
    let cells = '';
    for (const c of COLUMNS) {
      try { cells += cellHtml(c, s); } catch (e) { cells += '<td>' + DASH + '</td>'; report('scene ' + i + ' ' + c.key, e); }
    }
    tr.innerHTML = cells;
    const detail = document.createElement('tr');
    detail.className = 'detail';
    detail.hidden = true;
    const td = document.createElement('td');
    td.colSpan = COLUMNS.length;
    try { td.innerHTML = detailHtml(s, thumbs[i]); } catch (e) { report('detail of scene ' + i, e); }
    detail.appendChild(td);
    return {s: s, i: i, tr: tr, detail: detail, open: false,
            search: (show(s.scene) + ' ' + statusText(s) + ' ' + show(s.file)).toLowerCase()};
  });
  const byTr = new Map(rows.map((r) => [r.tr, r]));
  $('tbody').addEventListener('click', (ev) => {
    if (ev.target.closest('a')) return;
    const tr = ev.target.closest('tr.scene');
    const r = tr && byTr.get(tr);
    if (!r) return;
    r.open = !r.open;
    r.tr.classList.toggle('open', r.open);
    r.detail.hidden = !r.open;
  });
  $('thead').addEventListener('click', (ev) => {
    const th = ev.target.closest('th[data-key]');
    if (!th) return;
    const col = COLUMNS.find((c) => c.key === th.dataset.key);
    if (sortKey === col.key) sortDir = -sortDir; else { sortKey = col.key; sortDir = col.first; }
    sortRows();
  });
  $('filter').addEventListener('input', applyFilter);
  $('failedOnly').addEventListener('change', applyFilter);
  sortRows();
  applyFilter();
}

function sortRows() {
  const col = COLUMNS.find((c) => c.key === sortKey);
  const keyed = rows.map((r) => {
    let v = null;
    try { v = col.val(r.s); } catch (e) { report('sort ' + col.key, e); }
    return {r: r, v: v === undefined || (typeof v === 'number' && !isFinite(v)) ? null : v};
  });
  keyed.sort((a, b) => {
    if (a.v === null || b.v === null) return a.v === b.v ? a.r.i - b.r.i : a.v === null ? 1 : -1;
    if (a.v < b.v) return -sortDir;
    if (a.v > b.v) return sortDir;
    return a.r.i - b.r.i;
  });
  const frag = document.createDocumentFragment();
  for (const k of keyed) { frag.appendChild(k.r.tr); frag.appendChild(k.r.detail); }
  $('tbody').appendChild(frag);
  for (const th of $('thead').querySelectorAll('th')) {
    th.classList.toggle('sorted-desc', th.dataset.key === sortKey && sortDir < 0);
    th.classList.toggle('sorted-asc', th.dataset.key === sortKey && sortDir > 0);
  }
}

function applyFilter() {
  const q = $('filter').value.trim().toLowerCase();
  const failedOnly = $('failedOnly').checked;
  let shown = 0;
  for (const r of rows) {
    const on = (!q || r.search.includes(q)) && (!failedOnly || statusOf(r.s) !== 'ok');
    r.tr.hidden = !on;
    r.detail.hidden = !on || !r.open;
    if (on) ++shown;
  }
  $('shown').textContent = shown === rows.length ? rows.length + ' scenes' : shown + ' of ' + rows.length + ' scenes';
}

// ---- draw -----------------------------------------------------------------------------------
const t0 = performance.now();
for (const [name, part] of [['header', renderHeader], ['plots', renderPlots], ['table', renderTable]]) {
  try { part(); } catch (e) { report(name, e); }
}
document.body.dataset.rows = String(rows.length);
document.body.dataset.renderMs = (performance.now() - t0).toFixed(0);
document.body.dataset.rendered = '1';
})();
)JS";

// JSON for the inside of a <script> element. "<", ">" and "&" can only occur inside JSON strings,
// where their \u escapes mean the same to JSON.parse; without them no "</script>" or "<!--" in
// a scene's name can end the element early. Invalid UTF-8 becomes U+FFFD instead of throwing.
std::string ScriptSafeJson(const json& j) {
  const std::string raw = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(raw.size() + raw.size() / 16);
  for (const char c : raw) {
    switch (c) {
      case '<':
        out += "\\u003c";
        break;
      case '>':
        out += "\\u003e";
        break;
      case '&':
        out += "\\u0026";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Appends {name, href, jpeg} for the picture at `rel` (relative to sweep_dir) when it reads.
void AddThumbnail(const std::string& name, const json& rel, const fs::path& sweep_dir,
                  json* thumbs) {
  if (!rel.is_string() || rel.get<std::string>().empty()) return;
  const std::string path = rel.get<std::string>();
  const std::string jpeg = JpegThumbnail(sweep_dir / path);
  if (jpeg.empty()) return;
  thumbs->push_back({{"name", name}, {"href", path}, {"jpeg", Base64(jpeg)}});
}

// The thumbnails of one scene's `pictures`: segments, grasp, the servo pictures (each named by
// its file's stem), then any other picture fields in name order.
json SceneThumbnails(const json& scene, const fs::path& sweep_dir) {
  json thumbs = json::array();
  if (!scene.is_object() || !scene.contains("pictures") || !scene["pictures"].is_object())
    return thumbs;
  const json& pictures = scene["pictures"];
  const auto add_field = [&](const std::string& key, const json& value) {
    if (value.is_array()) {
      for (const json& p : value) {
        if (p.is_string())
          AddThumbnail(fs::path(p.get<std::string>()).stem().string(), p, sweep_dir, &thumbs);
      }
    } else {
      AddThumbnail(key, value, sweep_dir, &thumbs);
    }
  };
  const char* const kFirst[] = {"segments", "grasp", "servo"};
  for (const char* key : kFirst) {
    if (pictures.contains(key)) add_field(key, pictures[key]);
  }
  for (const auto& [key, value] : pictures.items()) {
    if (key != "segments" && key != "grasp" && key != "servo") add_field(key, value);
  }
  return thumbs;
}

}  // namespace

std::string Base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const uint32_t v = (uint32_t(uint8_t(bytes[i])) << 16) |
                       (uint32_t(uint8_t(bytes[i + 1])) << 8) | uint32_t(uint8_t(bytes[i + 2]));
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  const size_t rest = bytes.size() - i;
  if (rest > 0) {
    uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
    if (rest == 2) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string JpegThumbnail(const fs::path& path, int width_px) {
  std::error_code ec;
  if (width_px <= 0 || !fs::is_regular_file(path, ec)) return {};
  try {
    const cv::Mat image = cv::imread(path.string(), cv::IMREAD_COLOR);
    if (image.empty()) return {};
    const int height_px = std::max(1, int(std::lround(double(image.rows) * width_px / image.cols)));
    cv::Mat small;
    cv::resize(image, small, cv::Size(width_px, height_px), 0, 0,
               width_px < image.cols ? cv::INTER_AREA : cv::INTER_LINEAR);
    std::vector<uchar> jpeg;
    if (!cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, kThumbnailJpegQuality}))
      return {};
    return std::string(jpeg.begin(), jpeg.end());
  } catch (const cv::Exception&) {
    return {};  // a file OpenCV cannot decode is skipped like a missing one
  }
}

std::string ReportHtml(const json& summary, const fs::path& sweep_dir) {
  json thumbs = json::array();
  if (summary.is_object() && summary.contains("scenes") && summary["scenes"].is_array()) {
    for (const json& scene : summary["scenes"]) thumbs.push_back(SceneThumbnails(scene, sweep_dir));
  }
  const json data = {{"summary", summary}, {"thumbs", std::move(thumbs)}};

  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>hgrasp sweep report</title>\n<style>";
  html += kStyle;
  html += "</style>\n<script>";
  html += kErrorHandler;
  html += "</script>\n</head>\n<body>\n";
  html += R"HTML(<header>
<h1 id="title">hgrasp sweep</h1>
<div class="meta" id="meta"></div>
<div class="cards" id="cards"></div>
</header>
<pre id="errors"></pre>
<h2>Error distributions</h2>
<p class="muted">Histograms over every scene that has the figure; dashed lines: median (black) and
95th percentile (red). An orange bar on the right gathers a long tail.</p>
<div id="plots"></div>
<h2>Scenes</h2>
<div class="toolbar">
<input type="search" id="filter" placeholder="filter by scene, status or failure">
<label><input type="checkbox" id="failedOnly"> failed only</label>
<span class="muted" id="shown"></span>
<span class="legend muted">rows: <span style="background:#fbe3e1">failed</span><span
 style="background:#f4c7c3">crash</span><span style="background:#fbe7cf">timeout</span><span
 style="background:#ece1f5">bad input / error</span> &middot; click a header to sort (again to
reverse), a row for its pictures</span>
</div>
<table class="scenes"><thead id="thead"></thead><tbody id="tbody"></tbody></table>
)HTML";
  html += "<script type=\"application/json\" id=\"data\">";
  html += ScriptSafeJson(data);
  html += "</script>\n<script>";
  html += kScript;
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace hgrasp::app::sweep
