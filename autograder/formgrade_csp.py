"""A strict Content-Security-Policy on Formgrader's pages: no script runs but Formgrader's own.

Formgrader shows students' notebooks in the instructor's JupyterLab, on the same origin as the
Jupyter server's API: a script from a student's output would act with the instructor's rights.
``duckie formgrade`` loads this module as a Jupyter server extension. Every response under
``/formgrader`` then carries a policy that lets a script run only if it carries the response's
nonce (a new random one per response), or if it is one of Formgrader's five own ``onclick``
handlers (by their hash), and loads nothing from elsewhere: no external script,
image, font or connection, no plugin, no form sent elsewhere, no ``<base>``.

The nonce is given to Formgrader's own scripts only: those of the page before the notebook
(``id="notebook-container"``), inline or from the server's own path (``/...``). Nothing in the
notebook's part of the page gets it, so an inline handler (``onerror=``), a ``javascript:``
link or a ``<script>`` there does not run even if it got past the sanitising of
:func:`autograder.formgrade.for_formgrader`. A script tag of the page that names another site
(MathJax's CDN) is turned into one the browser does not fetch: the TeX of an answer shows as
typed.
"""

from __future__ import annotations

import base64
import hashlib
import re
import secrets
from typing import Any

__all__ = ["POLICY", "protect"]

#: Formgrader's own inline event handlers (its templates' ``onclick``), allowed by their hash:
#: these five exact texts run, no other handler does
#: (``tests/autograder/test_formgrade_safety.py`` reads them out of nbgrader's templates).
OWN_HANDLERS = (
    "toggle_name(true);",
    "toggle_name(false);",
    "toggleAllNames()",
    "createAssignmentModal();",
    "createStudentModal();",
)
_HASHES = " ".join(
    f"'sha256-{base64.b64encode(hashlib.sha256(text.encode()).digest()).decode()}'"
    for text in OWN_HANDLERS
)
#: The policy, with ``{nonce}`` for the response's nonce.
POLICY = (
    "default-src 'none'; script-src 'nonce-{nonce}' 'unsafe-hashes' "
    + _HASHES.replace("{", "{{").replace("}", "}}")
    + "; style-src 'self' 'unsafe-inline'; "
    "img-src 'self' data:; font-src 'self' data:; connect-src 'self'; form-action 'self'; "
    "base-uri 'none'; object-src 'none'; frame-ancestors 'self'"
)
#: Where the student's notebook begins on a submission's page.
NOTEBOOK_MARK = b'id="notebook-container"'
_SCRIPT = re.compile(rb"<script\b([^>]*)>", re.IGNORECASE)
_SOURCE = re.compile(rb"""\ssrc\s*=\s*["']?([^"'\s>]*)""", re.IGNORECASE)


def _own(attributes: bytes) -> bool:
    """Whether a script tag with ``attributes`` is inline or from this server's own path."""
    source = _SOURCE.search(attributes)
    if source is None:
        return True
    url = source.group(1)
    return url.startswith(b"/") and not url.startswith(b"//")


def protect(body: bytes, nonce: str) -> bytes:
    """``body`` (an HTML page) with the nonce on Formgrader's own scripts, and on none other."""
    mark = body.find(NOTEBOOK_MARK)
    page, notebook = (body, b"") if mark < 0 else (body[:mark], body[mark:])
    given = f' nonce="{nonce}"'.encode("ascii")

    def sign(found: re.Match) -> bytes:
        attributes = found.group(1)
        if not _own(attributes):  # from elsewhere: not even fetched
            return b'<script type="application/x-not-loaded">'
        if b"nonce" in attributes.lower():
            return found.group(0)
        return b"<script" + given + attributes + b">"

    return _SCRIPT.sub(sign, page) + notebook


def _jupyter_server_extension_points() -> list:
    return [{"module": "autograder.formgrade_csp"}]


def _load_jupyter_server_extension(serverapp: Any) -> None:
    """Put the policy on every response the server gives under ``/formgrader``."""
    from jupyter_server.utils import url_path_join
    from tornado import web

    prefix = url_path_join(serverapp.base_url, "formgrader")
    original = web.RequestHandler.flush
    if getattr(original, "duckie_policy", False):
        return

    def flush(self: web.RequestHandler, include_footers: bool = False) -> Any:
        if not self._headers_written and self.request.path.startswith(prefix):
            nonce = secrets.token_urlsafe(18)
            kind = str(self._headers.get("Content-Type", ""))
            if kind.startswith("text/html"):
                body = protect(b"".join(self._write_buffer), nonce)
                self._write_buffer = [body]
                if "Content-Length" in self._headers:
                    self.set_header("Content-Length", len(body))
            self.set_header("Content-Security-Policy", POLICY.format(nonce=nonce))
        return original(self, include_footers)

    flush.duckie_policy = True  # type: ignore[attr-defined]
    web.RequestHandler.flush = flush  # type: ignore[method-assign]
