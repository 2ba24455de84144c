// The viewer in a real browser (Debian's chromium, headless, driven by playwright-core):
//   node check_viewer.mjs --cli TDCR --scene GOOD.json --bad-scene BAD.json --out DIR
//        [--bench MODELS --moves N]
// Checks: the page loads and draws the robot (a screenshot with the robot's pixels); a slider
// move gives a new answer whose tip is the one `tdcr solve` computes for the same input; a bad
// scene shows its error (field and value) on the page; the server answers nothing but the
// loopback. With --bench: the latency from a slider move to the new picture, per model, over N
// moves (median and 90th percentile, ms), printed as one JSON line per model.
import { spawn, execFileSync } from "node:child_process";
import fs from "node:fs";
import net from "node:net";
import os from "node:os";
import path from "node:path";
import { chromium } from "playwright-core";

const args = Object.fromEntries(
  process.argv.slice(2).reduce((acc, a, i, all) => (a.startsWith("--") ? [...acc, [a.slice(2), all[i + 1]]] : acc), []));
const cli = args.cli, out = args.out || ".";
fs.mkdirSync(out, { recursive: true });
let failures = 0;
const check = (ok, what) => { console.log(`${ok ? "ok  " : "FAIL"} ${what}`); if (!ok) failures += 1; };

// Starts `tdcr view SCENE --port 0` and resolves with its address and process.
function startServer(scene) {
  return new Promise((resolve, reject) => {
    // Its own process group: the CLI runs python3 -m tdcr.view as a child, and both must stop.
    const p = spawn(cli, ["view", scene, "--port", "0"], { stdio: ["ignore", "pipe", "inherit"], detached: true });
    let text = "";
    const timer = setTimeout(() => reject(new Error("tdcr view printed no address in 30 s: " + text)), 30000);
    p.stdout.on("data", (d) => {
      text += d;
      const m = text.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (m) { clearTimeout(timer); resolve({ proc: p, url: m[0], port: Number(m[1]) }); }
    });
    p.on("exit", (code) => reject(new Error(`tdcr view exited with ${code}: ${text}`)));
  });
}

console.log("starting chromium");
const browser = await chromium.launch({
  timeout: 60000,
  executablePath: process.env.TDCR_CHROMIUM || "/usr/bin/chromium",
  args: ["--no-sandbox"],
});
const servers = [];
try {
  const good = await startServer(args.scene);
  servers.push(good);
  const page = await browser.newPage({ viewport: { width: 1000, height: 700 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  await page.goto(good.url);
  await page.waitForFunction(() => window.tdcrViewer && window.tdcrViewer.answers >= 1, null, { timeout: 60000 });

  if (args.bench) {
    // Latency: each move waits for its picture before the next (one solve per move).
    const models = args.bench.split(",");
    const moves = Number(args.moves || 50);
    for (const model of models) {
      const lat = await page.evaluate(async ({ model, moves }) => {
        const v = window.tdcrViewer;
        for (const c of document.querySelectorAll("#models input")) c.checked = c.value === model;
        document.querySelector("#models input").dispatchEvent(new Event("change"));
        const wait = (n) => new Promise((res) => { const t = () => (v.answers >= n && !v.inFlight ? res() : requestAnimationFrame(t)); t(); });
        await wait(v.answers + 1);
        const s = document.querySelector("input[data-tendon='0']");
        const lo = Number(s.min), hi = Number(s.max);
        v.latencies.length = 0;
        for (let i = 0; i < moves; ++i) {
          const n = v.answers + 1;
          s.value = lo + (hi - lo) * (0.2 + 0.3 * (i % 10) / 10);
          s.dispatchEvent(new Event("input"));
          await wait(n);
        }
        const l = v.latencies.slice().sort((a, b) => a - b);
        return { median_ms: l[Math.floor(l.length / 2)], p90_ms: l[Math.floor(0.9 * (l.length - 1))], moves: l.length,
                 ok: v.lastResults.every((r) => r.ok) };
      }, { model, moves });
      console.log(JSON.stringify({ model, scene: args.scene, ...lat }));
      check(lat.ok && lat.moves === moves, `${model}: ${moves} moves answered`);
    }
  } else {
    const first = await page.evaluate(() => window.tdcrViewer.lastResults);
    check(first.length >= 1 && first.every((r) => r.ok), `first answer converged (${first.map((r) => r.model)})`);
    // A screenshot with the robot in it: enough pixels of the model's colour.
    const shot = path.join(out, "viewer.png");
    await page.screenshot({ path: shot });
    const coloured = await page.evaluate(() => {
      const c = document.querySelector("#view canvas");
      const tmp = document.createElement("canvas");
      tmp.width = c.width; tmp.height = c.height;
      const g = tmp.getContext("2d");
      g.drawImage(c, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] - Math.max(d[i + 1], d[i + 2]) > 60) n += 1;  // red-ish: VC's colour
      return n;
    });
    check(coloured > 500, `the screenshot shows the robot (${coloured} pixels of VC's colour; ${shot})`);

    // Move the first tendon's slider: a new answer, its tip the one `tdcr solve` gives.
    const before = first[0].tip;
    const value = await page.evaluate(() => {
      const s = document.querySelector("input[data-tendon='0']");
      s.value = Number(s.min) + 0.3 * (Number(s.max) - Number(s.min));
      s.dispatchEvent(new Event("input"));
      return Number(s.value);
    });
    await page.waitForFunction(() => window.tdcrViewer.answers >= 2 && !window.tdcrViewer.inFlight);
    const after = await page.evaluate(() => window.tdcrViewer.lastResults[0]);
    const moved = Math.hypot(...after.tip.map((x, i) => x - before[i]));
    check(after.ok && moved > 1e-4, `the slider moved the tip by ${(1e3 * moved).toFixed(3)} mm`);
    const scene = JSON.parse(fs.readFileSync(args.scene, "utf8"));
    const key = scene.actuation.tensions ? "tensions" : "displacements";
    scene.actuation[key][0] = value;
    const moved_scene = path.join(out, "moved_scene.json");
    fs.writeFileSync(moved_scene, JSON.stringify(scene));
    const solved = JSON.parse(execFileSync(cli, ["solve", moved_scene, "--model", after.model, "--json"]).toString());
    const tip = solved.tip.position;
    const diff = Math.hypot(...after.tip.map((x, i) => x - tip[i]));
    check(diff < 1e-8, `(the default tip tolerance) the page's tip is tdcr solve's to ${diff.toExponential(2)} m`);
    check(errors.length === 0, `no script error on the page (${errors.join("; ")})`);

    // A bad scene: its error, naming the field and value, on the page.
    const bad = await startServer(args["bad-scene"]);
    servers.push(bad);
    const page2 = await browser.newPage();
    await page2.goto(bad.url);
    await page2.waitForFunction(() => window.tdcrViewer && window.tdcrViewer.ready, null, { timeout: 30000 });
    const shown = await page2.evaluate(() => (document.getElementById("error").hidden ? "" : document.getElementById("error").textContent));
    check(/robot\.segments\[0\]\.length/.test(shown) && /-0\.1/.test(shown), `the bad scene's error is on the page: "${shown}"`);

    // Loopback only: the server's port on another address of this machine refuses.
    const other = Object.values(os.networkInterfaces()).flat().find((a) => a && a.family === "IPv4" && !a.internal);
    if (!other) {
      console.log("skip no non-loopback IPv4 address on this machine: the loopback-only check needs one");
    } else {
      const refused = await new Promise((res) => {
        const s = net.connect({ host: other.address, port: good.port });
        s.on("connect", () => { s.destroy(); res(false); });
        s.on("error", (e) => res(e.code === "ECONNREFUSED"));
      });
      check(refused, `a connection to ${other.address}:${good.port} is refused`);
    }
  }
} finally {
  await browser.close();
  for (const s of servers) {
    try { process.kill(-s.proc.pid, "SIGINT"); } catch (e) { /* already gone */ }
  }
}
console.log(failures ? `${failures} check(s) failed` : "all checks passed");
process.exit(failures ? 1 : 0);
