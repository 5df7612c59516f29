"""What Formgrader shows of a student's work is made safe, and its pages run under a policy.

The browser test (``test_formgrade_browser.py``) opens a hostile submission in Chromium; these
check the two layers one by one, on the text itself.
"""

from __future__ import annotations

import json

from autograder.formgrade import for_formgrader, safe_markdown
from autograder.formgrade_csp import POLICY, protect


def _notebook(cells):
    return json.dumps({"cells": cells, "metadata": {}, "nbformat": 4, "nbformat_minor": 5})


def test_links_to_scripts_in_an_answer_lead_nowhere_and_web_links_stay():
    text = (
        "[a](javascript:alert(1)) [b]( JaVa&#x53;cript:alert(2)) [c](java\\script:x) "
        "[d](https://example.org/x) [e](#here) [f](data:text/html,x)\n\n[1]: vbscript:y\n"
        "[2]: mailto:a@b.c\n<img src=x onerror=alert(3)>"
    )
    shown = safe_markdown(text)
    assert "javascript" not in shown.lower().replace("&#x53;", "s")
    for gone in ("vbscript", "data:text", "<img"):
        assert gone not in shown
    for kept in ("(https://example.org/x)", "(#here)", "mailto:a@b.c", "&lt;img"):
        assert kept in shown


def test_outputs_keep_only_text_cleaned_html_and_pictures_of_a_numeric_size():
    output = {
        "output_type": "display_data",
        "data": {
            "image/png": "AAAA",
            "text/html": '<b>bold</b><script>x()</script><img src=y onerror="z()">'
            '<a href="javascript:w()">l</a>',
            "application/javascript": "evil()",
            "image/svg+xml": "<svg onload='evil()'/>",
            "text/plain": "ok",
        },
        "metadata": {
            "image/png": {"width": "1 onerror=evil()", "height": 20},
            "filenames": {"image/png": "http://outside.invalid/x.png"},
        },
    }
    code = {"cell_type": "code", "metadata": {}, "source": "", "outputs": [output],
            "execution_count": 1}  # fmt: skip
    shown = json.loads(for_formgrader(_notebook([code]), "03_frames", {}))["cells"][0]["outputs"]
    (kept,) = shown
    assert set(kept["data"]) == {"image/png", "text/html", "text/plain"}
    html = kept["data"]["text/html"]
    assert "<b>bold</b>" in html
    for gone in ("script", "onerror", "javascript"):
        assert gone not in html
    assert kept["metadata"] == {"image/png": {"height": 20}}


def test_only_the_pages_own_scripts_get_the_nonce_and_other_sites_are_not_fetched():
    page = (
        b'<html><head><script src="/formgrader/static/a.js"></script><script>var x = 1;</script>'
        b'<script src="https://cdn.example/mathjax.js"></script><script src="//cdn.example/b.js">'
        b'</script></head><body><div id="notebook-container"><script>evil()</script>'
        b'<script src="/files/submitted/ada/evil.js"></script></div></body></html>'
    )
    shown = protect(page, "N0NCE")
    head, notebook = shown.split(b'id="notebook-container"')
    assert head.count(b'nonce="N0NCE"') == 2
    assert b"cdn.example" not in head
    assert b"nonce" not in notebook
    assert "script-src 'nonce-N0NCE'" in POLICY.format(nonce="N0NCE")
    assert "'unsafe-inline'" not in POLICY.split("style-src")[0]


def test_the_policy_lets_every_inline_handler_of_formgraders_templates_run_and_no_other():
    # Read out of the installed nbgrader: a handler a new version adds shows here, not as a
    # dead button in the instructor's browser.
    import re
    from pathlib import Path

    from nbgrader.server_extensions import formgrader

    from autograder.formgrade_csp import OWN_HANDLERS

    templates = Path(formgrader.__file__).parent / "templates"
    handler = re.compile(r"""\son[a-z]+=(["'])(.*?)\1""", re.IGNORECASE)
    found = {
        match.group(2)
        for path in templates.rglob("*")
        if path.is_file()
        for match in handler.finditer(path.read_text(encoding="utf-8"))
    }
    assert found == set(OWN_HANDLERS)
