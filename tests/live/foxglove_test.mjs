// The mission over foxglove.websocket.v1, read by Foxglove's own client (@foxglove/ws-protocol):
// a launched mission advertises its channels with Foxglove's schema names; a subscriber gets
// every vehicle's pose (as many as the mission flies), the valves and XTs in a SceneUpdate, and
// the risk grid, whose cells integrate to the risk field's mass inside the workspace (about 1,
// computed here independently of the server); a client without the token, or with a wrong one,
// is refused in the handshake.
//
//   node foxglove_test.mjs --sage build/bin/sage --source-dir . --out build/foxglove_test
import path from "node:path";
import foxglove from "@foxglove/ws-protocol";
import WebSocket from "ws";
import { check, freshDir, liveEndpoints, parseArgs, run, stopAll, summary, waitFor } from "./common.mjs";

const { FoxgloveClient } = foxglove;  // a CommonJS package
const args = parseArgs(process.argv);
const out = freshDir(path.resolve(args.out));
const runDir = path.join(out, "run");
const VEHICLES = 5;
const VALVES = 20;  // fleet_field's
const XTS = 6;

function connect(url) {
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  return { ws, client: new FoxgloveClient({ ws }) };
}

// Does the handshake succeed? (resolves "open", or the HTTP status it was refused with)
function handshake(url) {
  return new Promise((resolve) => {
    const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
    ws.on("open", () => { ws.close(); resolve("open"); });
    ws.on("unexpected-response", (_request, response) => resolve(response.statusCode));
    ws.on("error", () => resolve("error"));
  });
}

async function main() {
  console.log("foxglove test: launching fleet_field with", VEHICLES, "vehicles");
  const launch = run(args.sage, [
    "launch", path.join(args["source-dir"], "scenarios/fleet_field.yaml"), "-n", String(VEHICLES),
    "--duration", "60", "--time-scale", "4", "--out", runDir, "--no-latest", "--http", "off",
  ]);
  const live = await liveEndpoints(runDir);
  check(live.http_port === -1 && live.foxglove_port > 0, `--http off: no page; Foxglove on ${live.foxglove_port}`);
  const base = `ws://127.0.0.1:${live.foxglove_port}/`;
  await waitFor("the launch to print the Foxglove address", () => launch.output.includes(`${base}?token=${live.token}`), 30000);
  check(true, "sage launch printed the Foxglove address with the token");

  check((await handshake(base)) === 403, "a client without the token is refused (403)");
  check((await handshake(`${base}?token=${"0".repeat(32)}`)) === 403, "a client with a wrong token is refused (403)");

  const { client } = connect(`${base}?token=${live.token}`);
  // Both come at once on connecting: listened for before either arrives.
  const infoCame = new Promise((resolve, reject) => {
    client.on("serverInfo", resolve);
    client.on("error", reject);
  });
  const channelsCame = new Promise((resolve) => client.on("advertise", resolve));
  const info = await infoCame;
  check(/SAGE Fleet/.test(info.name) && info.capabilities.includes("time"), `serverInfo: "${info.name}", ${JSON.stringify(info.capabilities)}`);
  const channels = await channelsCame;
  const byTopic = Object.fromEntries(channels.map((c) => [c.topic, c]));
  const expected = {
    "/sage/vehicles": "foxglove.PosesInFrame", "/sage/scene": "foxglove.SceneUpdate",
    "/sage/risk_grid": "foxglove.Grid", "/sage/mission": "sage.MissionStatus",
  };
  for (const [topic, schema] of Object.entries(expected)) {
    const c = byTopic[topic];
    check(c && c.schemaName === schema && c.encoding === "json" && c.schemaEncoding === "jsonschema" &&
          JSON.parse(c.schema).type === "object", `${topic} advertised as ${schema} (json, with a JSON Schema)`);
  }
  const latest = {};
  const subscriptions = {};
  let times = 0;
  client.on("time", () => { times++; });
  client.on("message", ({ subscriptionId, data }) => {
    const topic = subscriptions[subscriptionId];
    latest[topic] = JSON.parse(new TextDecoder().decode(data));
  });
  for (const topic of Object.keys(expected)) subscriptions[client.subscribe(byTopic[topic].id)] = topic;

  // Poses: every vehicle once all hosts are in.
  const poses = await waitFor("poses of every vehicle", () => latest["/sage/vehicles"] && latest["/sage/vehicles"].poses.length === VEHICLES ? latest["/sage/vehicles"] : null, 30000);
  check(poses.frame_id === "seabed" && poses.poses.length === VEHICLES, `/sage/vehicles: ${poses.poses.length} poses in "${poses.frame_id}"`);
  const q = poses.poses[0].orientation;
  check(Math.abs(Math.hypot(q.x, q.y, q.z, q.w) - 1) < 1e-3 && q.x === 0 && q.y === 0, "a pose's orientation is a unit yaw quaternion");
  const mission = await waitFor("a mission status past t = 0", () => latest["/sage/mission"] && latest["/sage/mission"].time_s > 0 ? latest["/sage/mission"] : null, 10000);
  check(mission.alive === VEHICLES && mission.time_s > 0, `/sage/mission: ${mission.alive} alive at t = ${mission.time_s} s`);
  check(times > 0, `the server publishes the mission clock (${times} time messages)`);

  // The scene goes out less often than the poses: the latest one may still be from before every
  // host was in (a loaded machine, chromium's test beside this one). Wait for one with every vehicle.
  const everyVehicle = (s) => s && s.entities.some((e) => e.id === "vehicles" && e.arrows.length === VEHICLES);
  const scene = await waitFor("a scene with every vehicle", () => everyVehicle(latest["/sage/scene"]) ? latest["/sage/scene"] : null, 10000);
  const entity = (id) => scene.entities.find((e) => e.id === id);
  check(entity("valves") && entity("valves").spheres.length === VALVES && entity("valves").texts.length === VALVES,
        `/sage/scene: ${entity("valves") ? entity("valves").spheres.length : 0} valve spheres with labels`);
  check(entity("structures") && entity("structures").cubes.length === XTS, `/sage/scene: ${XTS} XTs as cubes`);
  check(entity("vehicles") && entity("vehicles").arrows.length === VEHICLES, `/sage/scene: ${VEHICLES} vehicle arrows`);

  const grid = await waitFor("the risk grid", () => latest["/sage/risk_grid"], 10000);
  const bytes = Buffer.from(grid.data, "base64");
  const rows = bytes.length / grid.row_stride;
  check(grid.fields.length === 1 && grid.fields[0].type === 7 && grid.cell_stride === 4 && grid.row_stride === 4 * grid.column_count &&
        Number.isInteger(rows) && rows > 0, `/sage/risk_grid: ${grid.column_count} x ${rows} float32 cells of ${grid.cell_size.x.toFixed(3)} m`);
  // The density integrates to the mixture's mass inside the workspace: nearly all of it (valves
  // sit inside, 0.35 m spread), and never more than 1.
  let mass = 0;
  for (let i = 0; i < bytes.length; i += 4) mass += bytes.readFloatLE(i);
  mass *= grid.cell_size.x * grid.cell_size.y;
  check(mass > 0.95 && mass < 1.01, `the grid's cells integrate to ${mass.toFixed(4)} (the risk field's mass, within [0.95, 1.01])`);
  client.close();

  launch.kill("SIGINT");
  const exit = await launch.exited;
  check(exit.code === 130, `sage launch stopped on Ctrl-C (${JSON.stringify(exit)})`);
}

main()
  .catch((e) => { console.log(`  FAILED: ${e.stack || e}`); check(false, "the test ran to its end"); })
  .finally(() => {
    stopAll();
    process.exitCode = summary() ? 0 : 1;
  });
