// The live view in a real browser (Debian's chromium, headless, driven by playwright-core):
// a launched mission's page shows as many vehicles as the mission flies; a valve's risk changed
// from the page is applied (metrics.json `events`), while the same request with a wrong token,
// and with none, changes nothing; the page's screenshot is saved; the mission is stopped from
// the page; and `sage view` replays the finished run with its slider and play.
//
//   node browser_test.mjs --sage build/bin/sage --source-dir . --out build/live_view_test
import fs from "node:fs";
import path from "node:path";
import { chromium } from "playwright-core";
import {
  CHROMIUM_FLAGS, check, freshDir, liveEndpoints, parseArgs, readJson, run, stopAll, summary, vehiclesInRecord,
  waitFor,
} from "./common.mjs";

const args = parseArgs(process.argv);
const out = freshDir(path.resolve(args.out));
const runDir = path.join(out, "run");
const VEHICLES = 6;   // fleet_field flies 4; the launch asks for more, so the count is the launch's own
const RISK_VALVE = "P7", RISK_WEIGHT = "9";
const FORGED_VALVE = "P3";
let appliedAt = NaN;

async function main() {
  console.log("browser test: launching fleet_field with", VEHICLES, "vehicles");
  const launch = run(args.sage, [
    "launch", path.join(args["source-dir"], "scenarios/fleet_field.yaml"), "-n", String(VEHICLES),
    "--duration", "120", "--time-scale", "4", "--out", runDir, "--no-latest",
  ]);
  const live = await liveEndpoints(runDir);
  check(live.http_port > 0 && live.foxglove_port > 0, `live.json gives the ports (${live.http_port}, ${live.foxglove_port})`);
  check(/^[0-9a-f]{32}$/.test(live.token), "live_token holds a 128-bit token");
  check(live.tokenMode === 0o600, `live_token is the owner's alone (mode ${live.tokenMode.toString(8)})`);
  await waitFor("the launch to print the live view's address", () => launch.output.includes(`#token=${live.token}`), 30000);
  check(true, "sage launch printed the address with the token");

  const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: CHROMIUM_FLAGS });
  try {
    const page = await browser.newPage({ viewport: { width: 1400, height: 820 } });
    const errors = [];
    page.on("pageerror", (e) => errors.push(String(e)));
    page.on("dialog", (dialog) => dialog.accept());
    const base = `http://127.0.0.1:${live.http_port}/`;
    await page.goto(`${base}#token=${live.token}`);
    await page.waitForFunction(() => window.sageView && window.sageView.ready, null, { timeout: 30000 });
    // Every vehicle in by now (the launch starts all hosts before t = 0).
    const shown = await waitFor("the page to show the mission's vehicles", async () => {
      const text = await page.textContent("#vehicle-count");
      return Number(text) === VEHICLES ? text : null;
    }, 30000);
    // The record is flushed a second or more after the page has shown the vehicles (a loaded
    // machine had read trajectory.csv with its header alone).
    const record = await waitFor("trajectory.csv to hold the mission's vehicles", async () => {
      const n = vehiclesInRecord(runDir);
      return n === VEHICLES ? n : null;
    }, 30000);
    check(Number(shown) === VEHICLES && record === VEHICLES,
          `the page shows ${shown} vehicles alive; the mission flies ${VEHICLES} (trajectory.csv: ${record})`);
    const view = await page.evaluate(() => ({ ...window.sageView }));
    check(view.vehiclesShown === VEHICLES, `the page draws ${view.vehiclesShown} vehicles`);
    const framesBefore = view.frames;
    await page.waitForTimeout(1500);
    const later = await page.evaluate(() => ({ ...window.sageView }));
    check(later.frames > framesBefore + 5, `the page redraws (${later.frames - framesBefore} frames in 1.5 s)`);
    check(later.updateRate >= 5, `updates come at ${later.updateRate.toFixed(1)} a second (>= 5)`);
    check(later.time > view.time, `the mission clock moves (t = ${view.time.toFixed(1)} -> ${later.time.toFixed(1)} s)`);

    // Requests without the token, or with a wrong one: refused, and (checked at the end) nothing changes.
    const forged = await page.evaluate(async ([valve]) => {
      const body = new URLSearchParams({ verb: "risk", valve, weight: "50" }).toString();
      const headers = { "Content-Type": "application/x-www-form-urlencoded" };
      const none = await fetch("/api/action", { method: "POST", headers, body });
      const wrong = await fetch("/api/action", { method: "POST", headers: { ...headers, "X-Sage-Token": "0".repeat(32) }, body });
      const stop = await fetch("/api/action?token=" + "f".repeat(32), { method: "POST", headers, body: "verb=stop" });
      const data = await fetch("/api/frame");
      return [none.status, (await none.json()).line, wrong.status, (await wrong.json()).line, stop.status, data.status];
    }, [FORGED_VALVE]);
    check(forged[0] === 403 && /no token/.test(forged[1]), `no token: ${forged[0]} "${forged[1]}"`);
    check(forged[2] === 403 && /wrong token/.test(forged[3]), `a wrong token: ${forged[2]} "${forged[3]}"`);
    check(forged[4] === 403, `a stop with a wrong token: ${forged[4]}`);
    check(forged[5] === 403, `the mission's data without the token: ${forged[5]}`);

    // The operator's risk change, from the page's form.
    await page.fill("#risk-valve", RISK_VALVE);
    await page.fill("#risk-weight", RISK_WEIGHT);
    await page.click("#risk-form button");
    const answer = await waitFor("the server's answer", async () => {
      const text = await page.textContent("#answer");
      return text && text !== "…" ? text : null;
    }, 20000);
    const applied = new RegExp(`^${RISK_VALVE}: risk ${RISK_WEIGHT} applied at t = [0-9.]+ s; now [0-9.]+ % of the field's risk$`);
    check(applied.test(answer), `the page shows the answer sage risk set gives: "${answer}"`);
    appliedAt = Number((answer.match(/t = ([0-9.]+) s/) || [])[1]);
    await waitFor("the risk change in the event log", async () => (await page.textContent("#events")).includes(`${RISK_VALVE}: risk ${RISK_WEIGHT}`), 10000);
    check(true, "the event log shows the risk change");
    // The screenshot the README shows: the fleet a few mission seconds after the change.
    await page.waitForTimeout(2500);
    const shot = path.join(out, "live_view.png");
    await page.screenshot({ path: shot });
    check(fs.statSync(shot).size > 20000, `screenshot saved: ${shot}`);
    // A bad request is refused with the CLI's rule.
    await page.fill("#risk-valve", "NOPE");
    await page.fill("#risk-weight", "1");
    await page.click("#risk-form button");
    const refused = await waitFor("the refusal", async () => {
      const text = await page.textContent("#answer");
      return text && text !== "…" && !applied.test(text) ? text : null;
    }, 20000);
    check(/^valve = NOPE: not in this mission \(valves: P1, /.test(refused), `an unknown valve is refused: "${refused}"`);

    // Stop from the page: the server writes the run directory.
    await page.click("#stop-form button");
    const stopped = await waitFor("the stop's answer", async () => {
      const text = await page.textContent("#answer");
      return /^the mission stops at t = /.test(text || "") ? text : null;
    }, 20000);
    check(true, `the page stops the mission: "${stopped}"`);
    const exit = await Promise.race([launch.exited, new Promise((r) => setTimeout(() => r(null), 60000))]);
    check(exit && exit.code === 0, `sage launch ended (${JSON.stringify(exit)})`);
    if (errors.length) console.log("page errors:", errors);
    check(errors.length === 0, "no script error in the page");
  } finally {
    await browser.close();
  }

  const metrics = readJson(path.join(runDir, "metrics.json"));
  check(metrics.complete === true && metrics.stopped_early === true, "metrics.json is final, stopped early");
  const events = metrics.events.filter((e) => e.valve === RISK_VALVE);
  check(events.length === 1, `metrics.json events hold the page's change of ${RISK_VALVE} (${JSON.stringify(events)})`);
  if (events.length === 1) {
    // The answer gives the cycle that took the request; the change is in force from the next.
    check(Math.abs(events[0].time_s - appliedAt) <= 0.25,
          `metrics.json: applied at t = ${events[0].time_s} s, the page's answer said t = ${appliedAt} s`);
  }
  check(!metrics.events.some((e) => e.valve === FORGED_VALVE), `nothing changed ${FORGED_VALVE} (the requests without the right token)`);
  const risk = fs.readFileSync(path.join(runDir, "risk_events.csv"), "utf8");
  check(risk.includes(`${RISK_VALVE},${RISK_WEIGHT},`) && risk.includes("operator (live view)"),
        "risk_events.csv records the change from the live view");
  check(!risk.includes(`${FORGED_VALVE},50`), "risk_events.csv has no forged change");

  await replay();
}

// `sage view` on the finished run: the slider's time shows that time's fleet; play moves on.
async function replay() {
  console.log("browser test: sage view of the run");
  const viewer = run(args.sage, ["view", runDir]);
  const url = await waitFor("sage view's address", () => (viewer.output.match(/open (http:\/\/127\.0\.0\.1:\d+\/#token=[0-9a-f]{32})/) || [])[1], 60000);
  const browser = await chromium.launch({ executablePath: "/usr/bin/chromium", args: CHROMIUM_FLAGS });
  try {
    const page = await browser.newPage({ viewport: { width: 1400, height: 820 } });
    const errors = [];
    page.on("pageerror", (e) => errors.push(String(e)));
    await page.goto(url);
    await page.waitForFunction(() => window.sageView && window.sageView.ready, null, { timeout: 30000 });
    check((await page.textContent("#mode")) === "replay", "the page is in replay mode");
    check(await page.isVisible("#slider"), "the replay has a time slider");
    await page.$eval("#slider", (slider) => { slider.value = "10"; slider.dispatchEvent(new Event("input")); });
    await page.waitForFunction(() => Math.abs(window.sageView.time - 10) < 0.05, null, { timeout: 10000 });
    const at10 = await page.textContent("#vehicle-count");
    check(Number(at10) === VEHICLES, `at t = 10 s the replay shows ${at10} vehicles`);
    await page.click("#play");
    await page.waitForTimeout(1500);
    const t = await page.evaluate(() => window.sageView.time);
    check(t > 12, `play moves the clock (t = ${t.toFixed(1)} s after 1.5 s at 5x)`);
    await page.click("#play");
    await page.screenshot({ path: path.join(out, "replay.png") });
    const forbidden = await page.evaluate(async () => (await fetch("/api/frame?t=5")).status);
    check(forbidden === 403, `the replay's data without its token: ${forbidden}`);
    check(errors.length === 0, `no script error in the replay page ${errors.join("; ")}`);
  } finally {
    await browser.close();
    viewer.kill("SIGINT");
    await viewer.exited;
  }
}

main()
  .catch((e) => { console.log(`  FAILED: ${e.stack || e}`); check(false, "the test ran to its end"); })
  .finally(() => {
    stopAll();
    process.exitCode = summary() ? 0 : 1;
  });
