// What the live view's tests share: starting a mission with `sage launch` in a directory of the
// test's own, finding the live view's address and token it wrote, waiting for things, and
// checking them with a message that says what was expected. Every process started here is
// stopped when the test ends, also when it fails.
import { spawn } from "node:child_process";
import fs from "node:fs";
import path from "node:path";

export function parseArgs(argv) {
  const args = {};
  // --name value, or a flag alone (--secured): followed by another option or nothing, it is true.
  for (let i = 2; i < argv.length; i++) {
    if (!argv[i].startsWith("--")) throw new Error(`unexpected argument ${argv[i]}`);
    const value = argv[i + 1];
    if (value === undefined || value.startsWith("--")) {
      args[argv[i].slice(2)] = true;
    } else {
      args[argv[i].slice(2)] = value;
      i++;
    }
  }
  for (const key of ["sage", "source-dir", "out"]) {
    if (!args[key]) throw new Error(`give --${key}`);
  }
  return args;
}

export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

export async function waitFor(what, predicate, timeoutMs = 30000, everyMs = 100) {
  const until = Date.now() + timeoutMs;
  let last;
  while (Date.now() < until) {
    try {
      last = await predicate();
      if (last) return last;
    } catch (e) {
      last = e;
    }
    await sleep(everyMs);
  }
  throw new Error(`timed out after ${timeoutMs} ms waiting for ${what} (last: ${last})`);
}

let failures = 0, passes = 0;
export function check(condition, what) {
  if (condition) {
    passes++;
    console.log(`  ok: ${what}`);
  } else {
    failures++;
    console.log(`  FAILED: ${what}`);
  }
}
export function summary() {
  console.log(`${passes} passed, ${failures} failed`);
  return failures === 0 && passes > 0;
}

const children = [];
export function run(command, args, options = {}) {
  const child = spawn(command, args, Object.assign({ stdio: ["ignore", "pipe", "pipe"] }, options));
  child.output = "";
  child.stdout.on("data", (d) => { child.output += d; });
  child.stderr.on("data", (d) => { child.output += d; });
  child.exited = new Promise((resolve) => child.on("exit", (code, signal) => resolve({ code, signal })));
  children.push(child);
  return child;
}
export function stopAll() {
  for (const child of children) {
    if (child.exitCode === null && child.signalCode === null) child.kill("SIGINT");
  }
}
process.on("exit", () => {
  for (const child of children) {
    if (child.exitCode === null && child.signalCode === null) child.kill("SIGKILL");
  }
});

// A fresh directory for the test's runs (kept for a look afterwards).
export function freshDir(dir) {
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  return dir;
}

// The live view of a launched mission: its ports (live.json) and its token (live_token, 0600).
export async function liveEndpoints(runDir) {
  const endpoints = await waitFor("the server's live.json", () => {
    const file = path.join(runDir, "live.json");
    return fs.existsSync(file) ? JSON.parse(fs.readFileSync(file, "utf8")) : null;
  }, 60000);
  const tokenFile = path.join(runDir, "live_token");
  const stat = fs.statSync(tokenFile);
  const token = fs.readFileSync(tokenFile, "utf8").trim();
  return { ...endpoints, token, tokenMode: stat.mode & 0o777 };
}

export function readJson(file) {
  return JSON.parse(fs.readFileSync(file, "utf8"));
}

// The vehicles trajectory.csv names in its rows at the latest time written; 0 before its first
// rows are flushed (at least a second of wall time after they are flown).
export function vehiclesInRecord(runDir) {
  const lines = fs.readFileSync(path.join(runDir, "trajectory.csv"), "utf8").trim().split("\n").slice(1);
  if (lines.length === 0) return 0;
  const last = lines[lines.length - 1].split(",")[0];
  const names = new Set();
  for (let i = lines.length - 1; i >= 0; i--) {
    const [t, name] = lines[i].split(",");
    if (t !== last) break;
    names.add(name);
  }
  return names.size;
}

// Chromium as this machine runs it (Debian's, headless, no network of its own).
export const CHROMIUM_FLAGS = [
  "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync",
];
