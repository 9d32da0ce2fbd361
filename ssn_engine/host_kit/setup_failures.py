"""What went wrong in an engine set-up, in words that say what to do (stdlib only; the plug-ins carry a copy).

pip's and urllib's output is matched against known failures (a full disk, a
read-only folder, a proxy, TLS interception, no network); anything else is
named by its last line and the log.
"""

from __future__ import annotations

import re
import urllib.error
import urllib.request
from collections.abc import Mapping
from pathlib import Path

DEFAULT_INDEX = "https://pypi.org/simple"
PROXY_NAMES = ("HTTPS_PROXY", "https_proxy", "ALL_PROXY", "all_proxy")


class SetupError(RuntimeError):
    """The set-up cannot go on; the message says what to do."""


class SetupCancelled(SetupError):
    """The artist pressed Cancel."""


def index_url(env: Mapping[str, str]) -> str:
    return env.get("PIP_INDEX_URL") or DEFAULT_INDEX


_FAILURES: tuple[tuple[str, str], ...] = (
    (
        r"No space left on device|\[Errno 28\]",
        "The disk is full: {data} needs about 600 MB free. Free some space and press Set up again (it resumes).",
    ),
    (
        r"Read-only file system|Permission denied|\[Errno 13\]|\[Errno 30\]",
        "Cannot write to {data}. Make that folder writable (or set SSN_SHADOW_DATA to a writable folder before "
        "starting the program) and press Set up again.",
    ),
    (
        r"ProxyError|Cannot connect to proxy|407 Proxy Authentication",
        "The proxy refused the connection to {index}. Set HTTPS_PROXY (with its user and password if it needs them) "
        "or pip's proxy setting (pip.conf), then press Set up again.",
    ),
    (
        r"CERTIFICATE_VERIFY_FAILED|SSLError",
        "The secure connection to {index} failed (a proxy or firewall that intercepts HTTPS?). Set pip's 'cert' "
        "setting to your organisation's certificate, then press Set up again.",
    ),
    (
        r"NewConnectionError|Failed to establish a new connection|Temporary failure in name resolution|"
        r"Network is unreachable|Connection refused|ConnectTimeout|Read timed out|No matching distribution found",
        "Cannot reach the package index ({index}){proxy}. Check the network connection (or the proxy), then press "
        "Set up again: what was downloaded is kept.",
    ),
)


def url_opener(env: Mapping[str, str]) -> urllib.request.OpenerDirector:
    """urllib with the proxies of ``env`` (the set-up's environment, which pip gets too), not only this process's."""
    proxies = {}
    for scheme in ("http", "https"):
        proxy = env.get(f"{scheme.upper()}_PROXY") or env.get(f"{scheme}_proxy") or env.get("ALL_PROXY")
        if proxy:
            proxies[scheme] = proxy
    return urllib.request.build_opener(urllib.request.ProxyHandler(proxies))


def index_reachable(url: str, env: Mapping[str, str], timeout: float = 15.0) -> bool:
    """Whether the index answers at all (pip says only "no matching distribution" when it cannot reach it)."""
    try:
        with url_opener(env).open(url.rstrip("/") + "/", timeout=timeout):
            return True
    except urllib.error.HTTPError:
        return True  # it answered
    except Exception:
        return False


def explain_failure(output: str, data: Path, env: Mapping[str, str], what: str) -> str:
    """A message for people from a failed step's output."""
    for pattern, message in _FAILURES:
        if re.search(pattern, output):
            proxy = next((env[k] for k in PROXY_NAMES if env.get(k)), "")
            return message.format(data=data, index=index_url(env), proxy=f" through the proxy {proxy}" if proxy else "")
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    last = lines[-1] if lines else "no output"
    return f"{what} failed ({last}). The log {Path(data) / 'setup.log'} has the details; press Set up to try again."
