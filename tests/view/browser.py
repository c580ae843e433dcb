"""Headless Chromium driven over the Chrome DevTools protocol (the ``websockets`` client that viser
brings; no webdriver): open a page, run JavaScript, click, take PNG screenshots, list the URLs the
page requested.

Started with the flags a closed network needs (no background networking, updates or sync), a
fresh profile and software WebGL (SwiftShader), as ``apt-get install chromium`` provides it.
"""

from __future__ import annotations

import base64
import io
import itertools
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np

CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",  # WebGL on the CPU
    "--remote-debugging-port=0",
)


def chromium() -> str | None:
    """The Chromium executable, or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    """One headless Chromium with one page of ``size`` CSS pixels (device scale 1); ``flags`` are added
    to :data:`CHROMIUM_FLAGS`."""

    def __init__(
        self, executable: str, size: tuple[int, int] = (1400, 900), flags: tuple[str, ...] = ()
    ) -> None:
        from websockets.sync.client import connect

        self.profile = tempfile.mkdtemp(prefix="symkin-chromium-")
        self.log = open(os.path.join(self.profile, "chromium.log"), "w")  # noqa: SIM115
        args = [executable, *CHROMIUM_FLAGS, *flags, f"--user-data-dir={self.profile}", "about:blank"]
        self.proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=self.log)
        port_file = Path(self.profile, "DevToolsActivePort")
        deadline = time.monotonic() + 60
        while not (port_file.exists() and port_file.read_text().count("\n") >= 1):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                self.close()
                raise RuntimeError(f"chromium did not start; see {self.log.name}")
            time.sleep(0.05)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30) as r:
            page = next(p for p in json.load(r) if p["type"] == "page")
        self.ws = connect(page["webSocketDebuggerUrl"], max_size=None, open_timeout=30)
        self._ids = itertools.count(1)
        self._waiting: dict[int, queue.Queue] = {}
        self.events: list[dict] = []  # Network events of the page and its workers (see record_network)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self.send(
            "Emulation.setDeviceMetricsOverride",
            width=size[0], height=size[1], deviceScaleFactor=1, mobile=False,
        )  # fmt: skip

    def _read(self) -> None:
        """The DevTools messages, as they come: answers to their command's caller; a worker the
        page starts gets its Network events enabled before it runs; Network events are kept."""
        from websockets.exceptions import ConnectionClosed

        try:
            while True:
                msg = json.loads(self.ws.recv())
                if "id" in msg:
                    box = self._waiting.pop(msg["id"], None)
                    if box is not None:
                        box.put(msg)
                elif msg.get("method") == "Target.attachedToTarget":
                    session = msg["params"]["sessionId"]
                    for method in ("Network.enable", "Runtime.runIfWaitingForDebugger"):
                        self.ws.send(
                            json.dumps({"id": next(self._ids), "sessionId": session, "method": method})
                        )
                elif msg.get("method", "").startswith("Network."):
                    self.events.append(msg)
        except (ConnectionClosed, OSError):
            return

    def send(self, method: str, **params: Any) -> dict:
        """One DevTools command; its result."""
        i = next(self._ids)
        box: queue.Queue = queue.Queue()
        self._waiting[i] = box
        self.ws.send(json.dumps({"id": i, "method": method, "params": params}))
        msg = box.get(timeout=120)
        if "error" in msg:
            raise RuntimeError(f"{method}: {msg['error']}")
        return msg["result"]

    def record_network(self) -> None:
        """From now on, keep the Network events of the page and of every worker it starts."""
        self.send("Network.enable")
        self.send("Target.setAutoAttach", autoAttach=True, waitForDebuggerOnStart=True, flatten=True)

    def requested(self) -> list[str]:
        """Every URL the page and its workers asked for since :meth:`record_network` (documents,
        scripts, fonts, images, web sockets)."""
        urls = []
        for e in list(self.events):
            p = e.get("params", {})
            if e["method"] == "Network.requestWillBeSent":
                urls.append(p["request"]["url"])
            elif e["method"] == "Network.webSocketCreated":
                urls.append(p["url"])
        return urls

    def open(self, url: str) -> None:
        self.send("Page.navigate", url=url)

    def js(self, expression: str) -> Any:
        """The value of a JavaScript expression (promises awaited)."""
        r = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def click(self, x: float, y: float) -> None:
        """A left click at CSS pixel (x, y)."""
        self.send("Input.dispatchMouseEvent", type="mouseMoved", x=x, y=y)
        for kind in ("mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=1)

    def png(self) -> bytes:
        return base64.b64decode(self.send("Page.captureScreenshot", format="png")["data"])

    def screenshot(self, path: str | None = None) -> np.ndarray:
        """The page as RGB pixels (H, W, 3) uint8; also written to ``path`` as PNG."""
        from PIL import Image

        data = self.png()
        if path:
            with open(path, "wb") as f:
                f.write(data)
        return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))

    def settled(self, path: str | None = None, timeout: float = 60.0) -> np.ndarray:
        """A screenshot once rendering has settled: two in a row, 0.5 s apart, differing in fewer
        than 0.05% of pixels (software WebGL draws slowly; scenes fade in)."""
        last = self.screenshot()
        deadline = time.monotonic() + timeout
        while True:
            time.sleep(0.5)
            now = self.screenshot(path)
            changed = (np.abs(now.astype(int) - last).max(axis=-1) > 8).mean()
            if changed < 5e-4 or time.monotonic() > deadline:
                return now
            last = now

    def close(self) -> None:
        ws = getattr(self, "ws", None)
        if ws is not None:
            ws.close()
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)
