#!/usr/bin/env node
// Streams a G-code job from the real CNCjs server into a grbl board (`fpgacnc grbl`'s pty) through
// CNCjs's socket API, as its web page does: open the port as a Grbl controller, load the file,
// start it, follow the sender and the status reports until CNCjs itself ends the job, then print
// the final machine position.
//
// Usage: node drive_cncjs.js --modules DIR --pty PATH --job FILE --workdir DIR [--pause] [--reset]
//   --modules  the directory holding node_modules/ with cncjs, socket.io-client and jsonwebtoken
//   --workdir  where the CNCjs configuration (.cncrc) and HOME are put (created if missing)
//   --pause    pause the job (CNCjs's pause: `!` and the sender stops) a third of the way in,
//              wait for the machine to come to rest, check nothing was sent meanwhile, resume
//   --reset    before the job, start it and soft-reset (0x18) mid-job: the board must report
//              Alarm, `$X` (CNCjs's unlock) must bring it back to Idle
// Output: `final MPos X Y Z`, `steps/mm X Y Z` (the board's $100..$102), then `DONE`; exit status
// non-zero with a message naming what went wrong.
//
// Waits end on what the sender sees (an error or alarm line, the port closing, the workflow
// pausing on an error, no status report at all, or a line count that does not move), never on
// the machine's speed: the only wall-clock limit is HANG_S without any event from CNCjs, which
// only a hung process explains (CNCjs polls `?` every 250 ms and reports every change).
'use strict';

const { spawn } = require('child_process');
const crypto = require('crypto');
const fs = require('fs');
const path = require('path');

const HANG_S = 180; // seconds without a single event from CNCjs: a hung process
const STARTUP_S = 180; // seconds for the CNCjs server to start listening

function parseArgs(argv) {
  const a = { pause: false, reset: false };
  for (let i = 0; i < argv.length; i++) {
    const k = argv[i];
    if (k === '--pause') a.pause = true;
    else if (k === '--reset') a.reset = true;
    else if (['--modules', '--pty', '--job', '--workdir'].includes(k) && i + 1 < argv.length) {
      a[k.slice(2)] = argv[++i];
    } else {
      fail(`unknown or incomplete argument '${k}'`);
    }
  }
  for (const k of ['modules', 'pty', 'job', 'workdir']) {
    if (!a[k]) fail(`missing --${k}`);
  }
  return a;
}

let server = null;
let closing = false; // set when the driver closes the port itself
function fail(msg) {
  console.error(`drive_cncjs: FAIL: ${msg}`);
  if (server) server.kill('SIGTERM');
  process.exit(1);
}

const args = parseArgs(process.argv.slice(2));
const mod = (name) => require(path.join(path.resolve(args.modules), 'node_modules', name));
const io = mod('socket.io-client');
const jwt = mod('jsonwebtoken');
const cncjsBin = path.join(path.resolve(args.modules), 'node_modules', 'cncjs', 'bin', 'cncjs');

let gcode;
try {
  gcode = fs.readFileSync(args.job, 'utf8');
} catch (e) {
  fail(`cannot read the job ${args.job}: ${e.message}`);
}

// --- the CNCjs server ----------------------------------------------------------------------
fs.mkdirSync(args.workdir, { recursive: true });
const secret = crypto.randomBytes(16).toString('hex');
const config = path.join(path.resolve(args.workdir), 'cncrc.json');
fs.writeFileSync(config, JSON.stringify({
  secret,
  // /dev/pts/N is not in the system's serial port list: listed here, as docs/grbl.md says
  ports: [{ path: args.pty, manufacturer: 'fpgacnc grbl' }],
  // errors pause the job (CNCjs's default, written out: an error must not pass unseen)
  state: { controller: { exception: { ignoreErrors: false } } },
}, null, 2));

function startServer() {
  return new Promise((resolve) => {
    server = spawn(process.execPath,
      [cncjsBin, '--host', '127.0.0.1', '--port', '0', '--config', config],
      { env: { ...process.env, HOME: path.resolve(args.workdir), NODE_ENV: 'production' },
        stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    const timer = setTimeout(
      () => fail(`the CNCjs server did not listen within ${STARTUP_S} s:\n${out}`),
      STARTUP_S * 1000);
    const onData = (d) => {
      out += d.toString();
      // eslint-disable-next-line no-control-regex
      const m = out.replace(/\x1b\[[0-9;]*m/g, '')
        .match(/Starting the server at http:\/\/([\d.]+):(\d+)/);
      if (m) {
        clearTimeout(timer);
        server.stdout.removeListener('data', onData);
        server.stdout.resume();
        resolve(`http://${m[1]}:${m[2]}`);
      }
    };
    server.stdout.on('data', onData);
    server.stderr.on('data', (d) => { out += d.toString(); });
    server.on('exit', (code, sig) => fail(`the CNCjs server exited (${code ?? sig}):\n${out}`));
  });
}

// --- following CNCjs's events ------------------------------------------------------------------
const seen = {
  workflow: null, sender: null, status: null, settings: null, reads: [], statusReports: 0,
};
let waiter = null; // { pred, resolve, what }
let pendingCall = null; // a socket call waiting for its callback
let lastEvent = Date.now();

function check() {
  if (waiter && waiter.pred()) {
    const w = waiter;
    waiter = null;
    w.resolve();
  }
}

// Resolves when pred() holds after some event; the only limit is a hung CNCjs (no event at all).
function until(what, pred) {
  return new Promise((resolve) => {
    waiter = { pred, resolve, what };
    lastEvent = Date.now();
    check();
  });
}

setInterval(() => {
  const what = waiter ? waiter.what : pendingCall;
  if (what && Date.now() - lastEvent > HANG_S * 1000) {
    fail(`no event from CNCjs for ${HANG_S} s while waiting for ${what} (workflow ` +
      `${seen.workflow}, state ${activeState()}, sender ${JSON.stringify(senderCounts())})`);
  }
}, 1000).unref();

const activeState = () => (seen.status ? seen.status.activeState : undefined);
const mpos = () => (seen.status ? seen.status.mpos : undefined);
const senderCounts = () => (seen.sender
  ? { total: seen.sender.total, sent: seen.sender.sent, received: seen.sender.received }
  : {});

// What the sender must never see during these runs. `expectAlarm` is set while a reset is tested.
let expectAlarm = false;
function onRead(line) {
  seen.reads.push(line);
  if (/^error:/.test(line)) {
    fail(`the board answered '${line}' (last lines: ${seen.reads.slice(-4).join(' | ')})`);
  }
  if (/^ALARM:/.test(line) && !expectAlarm) fail(`unexpected '${line}'`);
}

function follow(socket) {
  const on = (ev, fn) => socket.on(ev, (...a) => { lastEvent = Date.now(); fn(...a); check(); });
  on('serialport:read', (data) => onRead(String(data).trim()));
  on('serialport:error', (e) => fail(`serial port error: ${JSON.stringify(e)}`));
  on('serialport:close', () => { if (!closing) fail('CNCjs closed the serial port'); });
  on('workflow:state', (s) => { seen.workflow = s; });
  on('sender:status', (s) => {
    seen.sender = s;
    if (s.hold && s.holdReason && s.holdReason.err) {
      fail(`CNCjs paused the job on an error: ${s.holdReason.msg}`);
    }
  });
  on('Grbl:state', (s) => { seen.status = s.status; seen.statusReports++; });
  on('Grbl:settings', (s) => { seen.settings = s.settings; });
  on('serialport:open', () => {});
  on('connect', () => {});
  on('disconnect', (r) => { if (!closing) fail(`socket disconnected from CNCjs: ${r}`); });
}

// While a job runs, the sender's received count must keep moving: counted in status reports.
// CNCjs sends `?` every 250 ms and reports every change, so STALL_REPORTS changed reports (the
// machine moving) without one more line acknowledged means lines are not being taken.
const STALL_REPORTS = 2000;
function progressing(pred, what) {
  let lastReceived = -1;
  let reportsAtLast = 0;
  return until(what, () => {
    if (pred()) return true;
    const r = seen.sender ? seen.sender.received : 0;
    if (r !== lastReceived) {
      lastReceived = r;
      reportsAtLast = seen.statusReports;
    } else if (seen.workflow === 'running' && seen.statusReports - reportsAtLast > STALL_REPORTS) {
      fail(`${STALL_REPORTS} status reports without a line acknowledged while waiting for ` +
        `${what} (sender ${JSON.stringify(senderCounts())}, state ${activeState()})`);
    }
    return false;
  });
}

// For the socket calls that answer through a callback (open, gcode:load).
function emitCb(socket, ...a) {
  return new Promise((resolve) => {
    pendingCall = `the answer to ${a[0]} ${a[0] === 'command' ? a[2] : ''}`;
    lastEvent = Date.now();
    socket.emit(...a, (err, data) => {
      pendingCall = null;
      if (err) fail(`${a[0]} ${a[2] || ''}: ${err.message || JSON.stringify(err)}`);
      resolve(data);
    });
  });
}

async function loadJob(socket, name) {
  const data = await emitCb(socket, 'command', args.pty, 'gcode:load', name, gcode, {});
  if (!data || !(data.total > 0)) fail(`gcode:load returned ${JSON.stringify(data)}`);
  await until('the loaded job in sender:status', () => seen.sender && seen.sender.name === name &&
    seen.sender.total === data.total && seen.workflow === 'idle');
  return data.total;
}

function fmt(p) {
  return `${p.x} ${p.y} ${p.z}`;
}

async function main() {
  const t0 = Date.now();
  const url = await startServer();
  const token = jwt.sign({ id: '', name: 'fpgacnc-test' }, secret, { expiresIn: '1d' });
  const socket = io.connect(url,
    { query: `token=${token}`, transports: ['websocket'], reconnection: false });
  socket.on('connect_error', (e) => fail(`cannot connect to CNCjs at ${url}: ${e.message || e}`));
  socket.on('error', (e) => fail(`socket error from CNCjs: ${e.message || JSON.stringify(e)}`));
  follow(socket);
  await until('the socket connection', () => socket.connected);
  const version = require(path.join(path.dirname(cncjsBin), '..', 'package.json')).version;
  console.log(`CNCjs ${version} at ${url}`);

  // Open: CNCjs waits for the banner, then sends $$, polls `?` and `$G`.
  await emitCb(socket, 'open', args.pty, { controllerType: 'Grbl', baudrate: 115200 });
  await until('the welcome banner', () => seen.reads.some((l) => /^Grbl 1\.1/.test(l)));
  await until('the $$ settings and an Idle status report', () => seen.settings &&
    seen.settings.$100 !== undefined && activeState() === 'Idle');
  const spm = ['$100', '$101', '$102'].map((k) => Number(seen.settings[k]));
  console.log(`opened ${args.pty}: ${seen.reads[seen.reads.findIndex((l) => /^Grbl/.test(l))]}, ` +
    `MPos ${fmt(mpos())}`);

  if (args.reset) {
    const total = await loadJob(socket, 'reset-' + path.basename(args.job));
    socket.emit('command', args.pty, 'gcode:start');
    const at = Math.max(1, Math.floor(total / 3));
    await progressing(() => seen.sender.received >= at && activeState() === 'Run',
      `${at} lines acknowledged with the machine running`);
    const sentAtReset = seen.sender.sent;
    expectAlarm = true;
    socket.emit('command', args.pty, 'reset');
    await until('Alarm after the soft reset', () => activeState() === 'Alarm');
    await until('the banner after the soft reset',
      () => seen.reads.filter((l) => /^Grbl 1\.1/.test(l)).length >= 2);
    if (seen.workflow !== 'idle') fail(`workflow ${seen.workflow} after reset, want idle`);
    const alarm = seen.reads.find((l) => /^ALARM:/.test(l));
    console.log(`reset after ${sentAtReset} lines sent: ${alarm || 'no ALARM line'}, ` +
      `state Alarm, MPos ${fmt(mpos())}`);
    if (!/^ALARM:3\b/.test(alarm || '')) {
      fail(`want ALARM:3 (reset while in motion), have ${alarm}`);
    }
    expectAlarm = false;
    socket.emit('command', args.pty, 'unlock');
    await until('Idle after $X', () => activeState() === 'Idle' &&
      seen.reads.some((l) => l === '[MSG:Caution: Unlocked]'));
    console.log('unlocked: Idle');
  }

  const total = await loadJob(socket, path.basename(args.job));
  console.log(`loaded ${args.job}: ${total} lines (with CNCjs's closing %wait)`);
  const tStart = Date.now();
  const reportsAtStart = seen.statusReports;
  socket.emit('command', args.pty, 'gcode:start');
  await until('the workflow running', () => seen.workflow === 'running');

  if (args.pause) {
    const at = Math.floor(total / 3);
    await progressing(() => seen.sender.received >= at, `${at} lines acknowledged`);
    socket.emit('command', args.pty, 'gcode:pause');
    await until('the workflow paused', () => seen.workflow === 'paused');
    if (seen.sender.sent >= total) {
      fail(`every line was sent before the pause at line ${at}: the job is too short for --pause`);
    }
    // Nothing more is sent and the machine comes to rest: Idle (a board without feed hold: the
    // lines in flight are answered and the queue runs out) or Hold:0 (the '!' held it mid-job;
    // lines in flight stay unanswered while the front end's pipeline is full, as on a grbl whose
    // planner buffer is full).
    await until('the machine at rest (Idle with every line sent answered, or Hold:0)', () =>
      (activeState() === 'Idle' && seen.sender.received === seen.sender.sent) ||
        (activeState() === 'Hold' && seen.status.subState === 0));
    // At rest with lines left: a sender that was not held would have sent them (the front end
    // takes lines whenever its look-ahead has room, and it is empty now).
    const held = { ...senderCounts() };
    const heldPos = fmt(mpos());
    if (held.sent >= total) fail(`sender sent every line while paused (${JSON.stringify(held)})`);
    console.log(`paused at line ${held.sent} of ${total}: machine at rest at ${heldPos}`);
    socket.emit('command', args.pty, 'gcode:resume');
    await until('the workflow running again', () => seen.workflow === 'running');
    console.log('resumed');
  }

  // CNCjs ends a job itself: every line answered, then the machine Idle for 500 ms -> gcode:stop.
  await progressing(() => seen.workflow === 'idle', 'CNCjs to end the job (workflow idle)');
  const s = senderCounts();
  if (s.received !== s.total || s.sent !== s.total) {
    fail(`job ended with sender ${JSON.stringify(s)}: not every line sent and answered`);
  }
  await until('an Idle status report', () => activeState() === 'Idle');
  const sec = (Date.now() - tStart) / 1000;
  const all = (Date.now() - t0) / 1000;
  console.log(`job done: ${s.total} lines sent and answered, ` +
    `${seen.statusReports - reportsAtStart} changed status reports, ${sec.toFixed(1)} s wall ` +
    `(all ${all.toFixed(1)} s)`);
  console.log(`final MPos ${fmt(mpos())}`);
  console.log(`steps/mm ${spm.join(' ')}`);
  closing = true;
  socket.emit('close', args.pty);
  socket.close();
  server.removeAllListeners('exit');
  server.kill('SIGTERM');
  console.log('DONE');
  process.exit(0);
}

main().catch((e) => fail(e.stack || String(e)));
