// What the live view costs and how fast it draws, measured (a benchmark: it prints and writes its
// figures, it asserts nothing). The same mission is launched again and again: with the live view
// off (--http off --foxglove off), on with nobody watching, and on with the page open in headless
// chromium for the whole mission; for each, the server's own cycle time (mean and p99, from its
// last lines), its real-time factor and lockstep, and with the page the page's own frame counter
// (redraws a second) and the frames it received a second. The machine's load average is noted
// before and after each run: on a shared machine the figures move with it.
//
//   build/bin/sage field generate --xts 300 --valves 1000 --vehicles 1000 --seed 1 -o /tmp/f1000.yaml
//   node tests/live/live_view_bench.mjs --sage build/bin/sage --source-dir . --out /tmp/live_bench \
//        --field /tmp/f1000.yaml --duration 60 --runs 2 [--configs off,idle,stream,viewer,viewer-niced,viewer-user,viewer-user-niced,viewer-user-idle,replay] [--secured]
//        [--page-fps N] [--cycle-priority N]
// (replay: the page alone, `sage view` of the run "off" just recorded, played at 1x, no mission running;
// viewer-niced: the page in a chromium run under `nice -n 19`, the browser taking only the CPU the
// mission leaves, as a browser on the operator's own machine would take none of the mission's
// (its session niced too: Playwright starts chromium in a session of its own, and where the
// kernel schedules sessions as groups, as here, a nice orders a process only within its session);
// viewer-user-idle: as viewer-user-niced, under SCHED_IDLE (`chrt --idle 0`) instead of nice 19;
// viewer-user / viewer-user-niced: the same as viewer / viewer-niced with chromium run as the
// unprivileged user nobody, as an operator's browser runs. Run as root, chromium raises its own
// display and compositor threads to nice -8 (its thread priorities; root may lower a nice value),
// above the mission's processes, and resets the nice 19 of viewer-niced; an unprivileged
// chromium cannot. Each run notes the lowest nice value seen among chromium's threads;
// stream: no browser, a client that reads the page's event stream (/api/stream, every frame the
// server sends a page) and draws nothing — the server's whole work for a watching page, as for a
// page on the operator's own machine, without a renderer on the mission's cores.)
import fs from "node:fs";
import http from "node:http";
import os from "node:os";
import path from "node:path";
import { chromium } from "playwright-core";
import { execSync } from "node:child_process";
import { CHROMIUM_FLAGS, freshDir, liveEndpoints, parseArgs, run, sleep, waitFor } from "./common.mjs";

const args = parseArgs(process.argv);
const out = freshDir(path.resolve(args.out));
const field = path.resolve(args.field || path.join(args["source-dir"], "scenarios/fleet_large.yaml"));
const duration = Number(args.duration || 60);
const runs = Number(args.runs || 1);
const configs = (args.configs || "off,idle,viewer").split(",");
const KNOWN_CONFIGS = ["off", "idle", "stream", "viewer", "viewer-niced", "viewer-user", "viewer-user-niced", "viewer-user-idle", "replay"];
for (const config of configs) {
  if (!KNOWN_CONFIGS.includes(config)) {
    console.error(`--configs: ${config}: not one of ${KNOWN_CONFIGS.join(", ")}`);
    process.exit(2);
  }
}
const extra = args.vehicles ? ["-n", args.vehicles] : [];
// --cycle-priority N: the server cycle's real-time priority for every launch (0: none; default: the launch's own, 10).
if (args["cycle-priority"] !== undefined) extra.push("--cycle-priority", String(args["cycle-priority"]));
const load = () => os.loadavg().map((x) => x.toFixed(2)).join(" ");
// CPU seconds used so far by every chromium process (user + system).
const chromiumCpu = () => {
  try {
    return Number(execSync("ps -C chromium -o cputimes= | awk '{s+=$1} END {print s+0}'").toString());
  } catch (e) {
    return NaN;
  }
};

// The lowest nice value among chromium's threads now (Infinity if none runs).
const chromiumLowestNice = () => {
  try {
    return Number(execSync("ps -eLo ni=,comm= | awk '$2 == \"chromium\" && (m == \"\" || $1 < m) {m = $1} END {print m == \"\" ? \"inf\" : m}'").toString());
  } catch (e) {
    return Infinity;
  }
};

// The chromium a configuration runs: Debian's, or a wrapper that lowers its priority and/or drops
// root. Unprivileged, chromium gets the profile directory playwright made for it and a home there.
function chromiumFor(config) {
  if (config === "viewer") return "/usr/bin/chromium";
  const niced = config.endsWith("-niced") ? "nice -n 19 " : config.endsWith("-idle") ? "chrt --idle 0 " : "";
  // Playwright starts the browser in a session of its own and, where the kernel groups the
  // scheduling of sessions (autogroups, /proc/sys/kernel/sched_autogroup_enabled), a process's
  // nice orders it only within its session: the session's own nice is what yields to the mission.
  const autogroup = config.endsWith("-niced") || config.endsWith("-idle") ? "echo 19 > /proc/self/autogroup 2>/dev/null; " : "";
  const user = config.startsWith("viewer-user");
  const wrapper = path.join(out, `chromium-${config}`);
  const body = user
    ? [
        "#!/bin/sh",
        'profile=$(printf "%s\\n" "$@" | sed -n "s/^--user-data-dir=//p" | head -1)',
        '[ -n "$profile" ] && chown -R nobody:nogroup "$profile"',
        `${autogroup}HOME="\${profile:-/tmp}" exec ${niced}setpriv --reuid=nobody --regid=nogroup --clear-groups --inh-caps=-all --bounding-set=-all /usr/bin/chromium "$@"`,
      ]
    : ["#!/bin/sh", `${autogroup}exec ${niced}/usr/bin/chromium "$@"`];
  fs.writeFileSync(wrapper, body.join("\n") + "\n", { mode: 0o755 });
  return wrapper;
}

function serverFigures(output) {
  const cycle = output.match(/server cycle ([0-9.]+) ms mean, ([0-9.]+) ms p99/);
  const factor = output.match(/\(([0-9.]+)x real time\)/);
  const lockstep = output.match(/(\d+) of (\d+) cycles in lockstep/);
  const onCpu = output.match(/cycle on the CPU ([0-9.]+) ms mean of its [0-9.]+ ms; switched out (\d+) times preempted/);
  const live = output.match(/live view: (\d+) frames, ([0-9.]+) ms a frame in the server's loop, ([0-9.]+) ms in the view's thread/);
  return {
    live_frames: live ? Number(live[1]) : 0,
    loop_copy_ms: live ? Number(live[2]) : NaN,
    view_thread_ms: live ? Number(live[3]) : NaN,
    cycle_mean_ms: cycle ? Number(cycle[1]) : NaN,
    cycle_p99_ms: cycle ? Number(cycle[2]) : NaN,
    cycle_cpu_ms: onCpu ? Number(onCpu[1]) : NaN,
    cycle_preemptions: onCpu ? Number(onCpu[2]) : NaN,
    real_time_factor: factor ? Number(factor[1]) : NaN,
    lockstep: lockstep ? `${lockstep[1]} of ${lockstep[2]}` : "?",
  };
}

async function once(config, k) {
  const dir = path.join(out, `${config}_${k}`);
  const launchArgs = ["launch", field, ...extra, "--duration", String(duration), "--out", dir, "--no-latest"];
  if (!args.secured) launchArgs.push("--insecure");
  if (config === "off") launchArgs.push("--http", "off", "--foxglove", "off");
  const before = load();
  const started = Date.now();
  const launch = run(args.sage, launchArgs);
  const result = { config, run: k, load_before: before };
  let browser = null;
  const samples = [];
  let stream = null;
  if (config === "stream") {
    const live = await liveEndpoints(dir);
    stream = { frames: 0, bytes: 0, request: null };
    await new Promise((resolve, reject) => {
      stream.request = http.get({ host: "127.0.0.1", port: live.http_port, path: `/api/stream?token=${live.token}` }, (res) => {
        if (res.statusCode !== 200) reject(new Error(`/api/stream answered ${res.statusCode}`));
        res.on("data", (chunk) => {
          stream.bytes += chunk.length;
          stream.frames += chunk.toString().split("\ndata: ").length - 1 + (chunk.toString().startsWith("data: ") ? 1 : 0);
        });
        res.on("end", () => {});
        resolve();
      });
      stream.request.on("error", () => {});
    });
  }
  if (config.startsWith("viewer")) {
    const live = await liveEndpoints(dir);
    browser = await chromium.launch({ executablePath: chromiumFor(config), args: CHROMIUM_FLAGS });
    const page = await browser.newPage({ viewport: { width: 1400, height: 820 } });
    // --page-fps N: the page's own cap on redraws (#fps=N; by default 30, and over 300 vehicles two a server frame).
    const fps = args["page-fps"] ? `&fps=${args["page-fps"]}` : "";
    await page.goto(`http://127.0.0.1:${live.http_port}/#token=${live.token}${fps}`);
    await page.waitForFunction(() => window.sageView && window.sageView.ready, null, { timeout: 120000 });
    // One sample a second while the mission runs (the page's counters are over its last second).
    const cpu0 = chromiumCpu(), wall0 = Date.now();
    let lowestNice = Infinity;
    while (launch.exitCode === null) {
      await sleep(1000);
      lowestNice = Math.min(lowestNice, chromiumLowestNice());
      try {
        const v = await page.evaluate(() => ({ fps: window.sageView.fps, rate: window.sageView.updateRate,
                                                vehicles: window.sageView.vehiclesShown, t: window.sageView.time }));
        if (v.vehicles > 0) samples.push(v);
      } catch (e) {
        break;
      }
    }
    result.chromium_cores = (chromiumCpu() - cpu0) / ((Date.now() - wall0) / 1000);
    result.chromium_lowest_nice = lowestNice;
    await page.screenshot({ path: path.join(out, `${config}_${k}.png`) }).catch(() => {});
  }
  const exit = await launch.exited;
  if (browser) await browser.close();
  if (stream) {
    stream.request.destroy();
    Object.assign(result, { stream_frames: stream.frames, stream_mb: stream.bytes / 1e6 });
  }
  Object.assign(result, serverFigures(launch.output), { exit: exit.code, wall_s: (Date.now() - started) / 1000, load_after: load() });
  if (samples.length) {
    // The first seconds are start-up (every host joining); the figures are of the steady part.
    const steady = samples.filter((s) => s.vehicles === Math.max(...samples.map((x) => x.vehicles))).slice(2);
    const fps = steady.map((s) => s.fps).sort((a, b) => a - b);
    const rate = steady.map((s) => s.rate).sort((a, b) => a - b);
    const pick = (xs, q) => xs[Math.min(xs.length - 1, Math.floor(q * xs.length))];
    Object.assign(result, {
      vehicles_shown: steady.length ? steady[0].vehicles : 0, seconds_sampled: steady.length,
      fps_min: fps[0], fps_median: pick(fps, 0.5), fps_p10: pick(fps, 0.1),
      updates_min: rate[0], updates_median: pick(rate, 0.5),
    });
  }
  fs.writeFileSync(path.join(dir, "launch.log"), launch.output);
  console.log(JSON.stringify(result));
  return result;
}

// The page alone, with no mission running: `sage view` of a run just recorded, played at 1x.
async function replay(dir, k) {
  const before = load();
  const viewer = run(args.sage, ["view", dir]);
  const url = await waitFor("sage view's address", () => (viewer.output.match(/open (http:\/\/\S+)/) || [])[1], 300000);
  const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: CHROMIUM_FLAGS });
  const page = await browser.newPage({ viewport: { width: 1400, height: 820 } });
  await page.goto(url);
  await page.waitForFunction(() => window.sageView && window.sageView.ready, null, { timeout: 60000 });
  await page.selectOption("#speed", "1");
  await page.click("#play");
  await sleep(3000);
  const cpu0 = chromiumCpu(), wall0 = Date.now();
  const fps = [];
  for (let i = 0; i < Math.min(40, duration - 5); i++) {
    await sleep(1000);
    fps.push(await page.evaluate(() => window.sageView.fps));
  }
  const cores = (chromiumCpu() - cpu0) / ((Date.now() - wall0) / 1000);
  await browser.close();
  viewer.kill("SIGINT");
  await viewer.exited;
  fps.sort((a, b) => a - b);
  const result = { config: "replay", run: k, load_before: before, load_after: load(), chromium_cores: cores,
                   fps_min: fps[0], fps_p10: fps[Math.floor(0.1 * fps.length)], fps_median: fps[Math.floor(0.5 * fps.length)],
                   loop_copy_ms: NaN, cycle_mean_ms: "-", cycle_p99_ms: "-", real_time_factor: "-", lockstep: "-" };
  console.log(JSON.stringify(result));
  return result;
}

const results = [];
for (let k = 0; k < runs; k++) {
  for (const config of configs) {
    results.push(config === "replay" ? await replay(path.join(out, `off_${k}`), k) : await once(config, k));
  }
}
fs.writeFileSync(path.join(out, "live_view_bench.json"), JSON.stringify({ field, duration, results }, null, 2));
const rows = results.map((r) =>
  `| ${r.config} | ${r.run} | ${r.cycle_mean_ms} / ${r.cycle_p99_ms} | ${r.cycle_cpu_ms ?? "-"} / ${r.cycle_preemptions ?? "-"} | ${r.real_time_factor}x | ${r.lockstep} | ` +
  `${r.fps_median === undefined ? "-" : `${r.fps_min.toFixed(1)} / ${r.fps_p10.toFixed(1)} / ${r.fps_median.toFixed(1)}`} | ` +
  `${r.stream_frames !== undefined ? `${(r.stream_frames / duration).toFixed(1)} a second read (${r.stream_mb.toFixed(1)} MB)`
    : r.updates_median === undefined ? "-" : `${r.updates_min.toFixed(1)} / ${r.updates_median.toFixed(1)}`} | ` +
  `${r.chromium_cores === undefined ? "-" : r.chromium_cores.toFixed(2)} | ` +
  `${r.chromium_lowest_nice === undefined ? "-" : r.chromium_lowest_nice} | ` +
  `${Number.isNaN(r.loop_copy_ms) ? "-" : `${r.loop_copy_ms} / ${r.view_thread_ms}`} | ${r.load_before} -> ${r.load_after} |`);
const table = [
  `${field}, ${duration} s per run`,
  "",
  "| live view | run | server cycle mean / p99 (ms) | on its CPU (ms) / preempted | real time | cycles in lockstep | page frames/s min / p10 / median | updates/s min / median | chromium (cores) | chromium's lowest nice | view's ms a frame: loop / own thread | load average before -> after |",
  "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
  ...rows,
].join("\n");
fs.writeFileSync(path.join(out, "live_view_bench.md"), table + "\n");
console.log(table);
