// What the browser tests share: a counted `test`, `assert`, the run's last line
// ('N passed, N failed', exit 1 on any failure, a crash of the run counted as one failure), and a
// fresh headless Debian chromium (playwright-core) in a profile of its own.
//
// Usage: `const t = suite();` then `await t.test(name, fn)`, `t.assert(cond, message)`, and
// `t.run(main)` as the module's last statement (main may call `t.finish(lines)` itself to print
// figures before the last line).
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { chromium } from 'playwright-core';

/// A counter of passed and failed tests for one script.
export function suite() {
  let passed = 0;
  let failed = 0;
  const s = {
    /// Runs `fn` as the test `name`, printing 'ok' with its time or 'FAIL' with the error.
    async test(name, fn) {
      const t0 = Date.now();
      try {
        await fn();
        passed++;
        console.log(`ok    ${name} (${Date.now() - t0} ms)`);
      } catch (e) {
        failed++;
        console.log(`FAIL  ${name}: ${e && e.stack ? e.stack : e}`);
      }
    },
    /// Throws `message` unless `cond`.
    assert(cond, message) {
      if (!cond) throw new Error(message);
    },
    /// Prints `lines` (figures), then 'N passed, N failed', and exits: 0 only when none failed.
    finish(lines = []) {
      for (const l of lines) console.log(l);
      console.log(`${passed} passed, ${failed} failed`);
      process.exit(failed === 0 ? 0 : 1);
    },
    /// Runs `main`, then `finish()`; a crash of the run is one more failure.
    run(main) {
      main()
        .then(() => s.finish())
        .catch((e) => {
          console.log(`FAIL  the test run: ${e && e.stack ? e.stack : e}`);
          failed++;
          s.finish();
        });
    },
  };
  return s;
}

/// Headless chromium (`CHROMIUM`, default /usr/bin/chromium) in a fresh profile under the
/// system's temporary folder, `extraArgs` added to its switches and `options` to playwright's;
/// returns `{ context, profile }` (remove `profile` after `context.close()`).
export async function launch(prefix, extraArgs = [], options = {}) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), prefix));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking', '--disable-component-update', '--disable-sync', ...extraArgs],
    ...options,
  });
  return { context, profile };
}
