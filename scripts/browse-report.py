#!/usr/bin/env python3
"""Open a report.html in headless Chromium and say what a reader's browser saw, as JSON on stdout.

    scripts/browse-report.py REPORT_HTML SCREENSHOT_PNG [CHROMIUM]

Chromium (Debian's `chromium`) is driven through the Chrome DevTools Protocol over a pipe
(`--remote-debugging-pipe`: file descriptors 3 and 4, messages of JSON each ended by a NUL byte),
so nothing but Python's standard library and the browser is needed. Every request that is not
the page itself or a data: URI is intercepted (Fetch domain) and failed, and recorded. The page
is loaded in a 1366 x 768 viewport (a laptop screen); then the script records the console errors
and exceptions (and the log's errors: a Content-Security-Policy violation is one), every image's
naturalWidth, the cells of every table (text and data attributes), the page's scroll width, and
writes a full-page screenshot. tests/report_html.rs runs it and checks the answers.
"""
import base64
import fcntl
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

TIMEOUT_S = 90.0

EXTRACT = r"""
JSON.stringify({
  images: Array.from(document.images).map(i => ({alt: i.alt, complete: i.complete, naturalWidth: i.naturalWidth,
                                                 scheme: i.src.split(':')[0]})),
  cells: Array.from(document.querySelectorAll('td')).map(td => ({
    table: (td.closest('table') || {}).id || (td.closest('table') || {}).dataset.file || '',
    row: (td.closest('tr') || {}).dataset ? td.closest('tr').dataset.row : undefined,
    missed: td.closest('tr').classList.contains('missed'),
    score: td.dataset.score, value: td.dataset.value, ci95: td.dataset.ci95, column: td.dataset.column,
    text: td.innerText})),
  scrollWidth: document.documentElement.scrollWidth,
  scriptCount: document.scripts.length,
  title: document.title,
  bodyText: document.body.innerText.length
})
"""


class Browser:
    def __init__(self, chromium, profile):
        to_chrome_r, self.to_chrome = os.pipe()
        self.from_chrome, from_chrome_w = os.pipe()
        # Copies above the low numbers, so that moving them to 3 and 4 cannot clobber one another.
        high = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_chrome_r, from_chrome_w)]

        def child_fds():
            os.dup2(high[0], 3)
            os.dup2(high[1], 4)

        args = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run", "--no-default-browser-check",
                "--disable-extensions", "--mute-audio", f"--user-data-dir={profile}", "--remote-debugging-pipe",
                "about:blank"]
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, close_fds=False, preexec_fn=child_fds)
        for fd in (to_chrome_r, from_chrome_w, *high):
            os.close(fd)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        self.deadline = time.monotonic() + TIMEOUT_S

    def send(self, method, params=None, session=None):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_chrome, json.dumps(msg).encode() + b"\0")
        return self.next_id

    def read_message(self):
        while b"\0" not in self.buffer:
            left = self.deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("Chromium did not answer in time")
            ready, _, _ = select.select([self.from_chrome], [], [], left)
            if ready:
                chunk = os.read(self.from_chrome, 1 << 20)
                if not chunk:
                    raise RuntimeError("Chromium closed its pipe: " + self.proc.stderr.read().decode(errors="replace")[-2000:])
                self.buffer += chunk
        raw, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(raw)

    def call(self, method, params=None, session=None):
        want = self.send(method, params, session)
        while True:
            msg = self.read_message()
            if msg.get("id") == want:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_event(self, name):
        for i, e in enumerate(self.events):
            if e.get("method") == name:
                return self.events.pop(i)
        while True:
            msg = self.read_message()
            if msg.get("method") == name:
                return msg
            self.events.append(msg)

    def close(self):
        try:
            self.send("Browser.close")
        except OSError:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def main():
    page, screenshot = os.path.abspath(sys.argv[1]), sys.argv[2]
    chromium = sys.argv[3] if len(sys.argv) > 3 else shutil.which("chromium") or "chromium"
    url = "file://" + page
    profile = tempfile.mkdtemp(prefix="inimtrace-chromium-")
    browser = Browser(chromium, profile)
    try:
        target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            browser.call(f"{domain}.enable", {}, session)
        browser.call("Fetch.enable", {"patterns": [{"urlPattern": "*"}]}, session)
        browser.call("Emulation.setDeviceMetricsOverride",
                     {"width": 1366, "height": 768, "deviceScaleFactor": 1, "mobile": False}, session)
        nav = browser.send("Page.navigate", {"url": url}, session)
        requests, blocked, errors = [], [], []
        loaded = False
        while not loaded:
            msg = browser.read_message()
            method = msg.get("method")
            p = msg.get("params", {})
            if msg.get("id") == nav and "error" in msg:
                raise RuntimeError(f"Page.navigate: {msg['error']}")
            if method == "Fetch.requestPaused":
                req_url = p["request"]["url"]
                if req_url == url or req_url.startswith("data:"):
                    browser.send("Fetch.continueRequest", {"requestId": p["requestId"]}, session)
                else:
                    blocked.append(req_url)
                    browser.send("Fetch.failRequest", {"requestId": p["requestId"], "errorReason": "BlockedByClient"},
                                 session)
            elif method == "Network.requestWillBeSent":
                requests.append(p["request"]["url"][:200])
            elif method == "Page.loadEventFired":
                loaded = True
            else:
                browser.events.append(msg)
        result = json.loads(browser.call("Runtime.evaluate", {"expression": EXTRACT, "returnByValue": True},
                                         session)["result"]["value"])
        shot = browser.call("Page.captureScreenshot", {"format": "png", "captureBeyondViewport": True}, session)
        with open(screenshot, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        # Whatever arrived meanwhile: console errors, exceptions, the log's errors.
        for e in browser.events:
            method, p = e.get("method"), e.get("params", {})
            if method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                errors.append("console: " + " ".join(str(a.get("value", a.get("description", ""))) for a in p["args"]))
            elif method == "Runtime.exceptionThrown":
                errors.append("exception: " + json.dumps(p.get("exceptionDetails", {}))[:500])
            elif method == "Log.entryAdded" and p["entry"].get("level") == "error":
                errors.append("log: " + p["entry"].get("text", ""))
            elif method == "Network.requestWillBeSent":
                requests.append(p["request"]["url"][:200])
        result.update({"url": url, "console_errors": errors, "blocked_requests": blocked,
                       "requests": [r for r in requests if r != url and not r.startswith("data:")]})
        print(json.dumps(result))
    finally:
        browser.close()
        shutil.rmtree(profile, ignore_errors=True)


if __name__ == "__main__":
    main()
