"""The report's Markdown as one HTML page that reads offline: formulas as MathML, no script, no network.

:func:`markdown_to_html` knows the Markdown the report of :mod:`symvib.paper.report` is written in
(headings, paragraphs, lists, tables, figures with their captions, links, bold, italics, code
spans); a formula (``$...$``, ``$$...$$``, not inside a code span) becomes MathML by
:mod:`symvib.paper.texmathml`, or stays TeX in ``<code>`` outside its subset.

Examples
--------
>>> formulas("a $x^2$, `$kept$` and $$y$$")
['x^2', 'y']
>>> page = markdown_to_html("## Two runs\\n\\n**one** event, $k = 1$", title="t")
>>> page.splitlines()[3]
'<h2 id="two-runs">Two runs</h2>'
"""
from __future__ import annotations

import html
import re

from symvib.paper.texmathml import to_mathml

__all__ = ["HTML_STYLE", "MATH", "formulas", "markdown_to_html"]


#: Style of the HTML report (no external resource: the report reads offline).
HTML_STYLE = ("body{font-family:sans-serif;max-width:70em;margin:auto;padding:0 1em} table{border-collapse:collapse}"
              " td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%} figure{display:inline-block;"
              "width:48%;margin:0.5em 0.5%;vertical-align:top} figure img{width:100%}"
              " figcaption{font-size:85%;color:#333}"
              " math[display=block]{margin:0.6em 0;padding:0.4em 0;overflow-x:auto;overflow-y:hidden}"
              " code.tex{color:#555}")
#: Math in a Markdown line: display ``$$...$$`` or inline ``$...$``.
MATH = re.compile(r"\$\$(.+?)\$\$|(?<![\\$])\$([^$\n]+?)\$")
#: A code span (kept as it is: the seed's texts hold ``$``) or math, whichever comes first.
_CODE_OR_MATH = re.compile(r"`([^`\n]+)`|" + MATH.pattern)


def formulas(text: str) -> list:
    """The TeX of every formula of Markdown ``text`` (not those inside code spans)."""
    return [m.group(2) or m.group(3) for m in _CODE_OR_MATH.finditer(text) if m.group(1) is None]


def _math_html(tex: str, display: bool) -> str:
    """A formula as MathML, or its TeX in ``<code>`` outside :mod:`symvib.paper.texmathml`'s subset."""
    out = to_mathml(tex, display=display)
    return out if out is not None else f'<code class="tex">{html.escape(tex, quote=False)}</code>'


def _inline(s: str) -> str:
    """Markdown inline constructs of the report (images, links, bold, italics, code) and math as MathML."""
    parts = []
    last = 0
    for m in _CODE_OR_MATH.finditer(s):
        parts.append(_inline_text(s[last:m.start()]))
        if m.group(1) is not None:
            parts.append(f"<code>{html.escape(m.group(1), quote=False)}</code>")
        else:
            display = m.group(2) is not None
            parts.append(_math_html(m.group(2) if display else m.group(3), display))
        last = m.end()
    parts.append(_inline_text(s[last:]))
    return "".join(parts)


def _inline_text(s: str) -> str:
    s = html.escape(s, quote=False)
    s = re.sub(r"!\[([^\]]*)\]\(([^)]+)\)", r'<img alt="\1" src="\2">', s)
    s = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', s)
    s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
    s = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", s)
    s = re.sub(r"(?<![*\w])\*([^*\s][^*]*?)\*(?![*\w])", r"<em>\1</em>", s)
    return s


def markdown_to_html(text: str, *, title: str) -> str:
    """The report's Markdown as one self-contained HTML page: tables, lists, figures with their
    captions, and formulas as MathML (:mod:`symvib.paper.texmathml`), so it needs no script and no network."""
    body = []
    table = []
    items = []

    def flush():
        if table:
            rows = [r for r in table if not re.match(r"^\|\s*:?-", r)]
            cells = [[c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", r.strip()[1:-1])]
                     for r in rows]
            tag = lambda i: "th" if i == 0 else "td"  # noqa: E731
            out = ["<table>"] + ["<tr>" + "".join(f"<{tag(i)}>{_inline(c)}</{tag(i)}>" for c in row) + "</tr>"
                                 for i, row in enumerate(cells)] + ["</table>"]
            body.append("\n".join(out))
            table.clear()
        if items:
            body.append("<ul>\n" + "\n".join(f"<li>{_inline(i)}</li>" for i in items) + "\n</ul>")
            items.clear()

    lines = text.splitlines()
    k = 0
    while k < len(lines):
        line = lines[k]
        k += 1
        if line.startswith("|"):
            if items:
                flush()
            table.append(line)
            continue
        if line.startswith("- "):
            if table:
                flush()
            items.append(line[2:])
            continue
        flush()
        m = re.match(r"^(#{1,4}) (.*)$", line)
        image = re.match(r"^!\[([^\]]*)\]\(([^)]+)\)$", line)
        if m:
            level = len(m.group(1))
            anchor = re.sub(r"[^a-z0-9 -]", "", m.group(2).lower()).replace(" ", "-")
            body.append(f'<h{level} id="{anchor}">{_inline(m.group(2))}</h{level}>')
        elif image:
            # A figure; its caption is the next paragraph when it is in italics.
            j = k
            while j < len(lines) and not lines[j].strip():
                j += 1
            cap = ""
            if j < len(lines) and re.match(r"^\*[^*].*\*$", lines[j]):
                cap = f"<figcaption>{_inline(lines[j][1:-1])}</figcaption>"
                k = j + 1
            alt, src = (html.escape(g, quote=True) for g in image.groups())
            body.append(f'<figure><img alt="{alt}" src="{src}">{cap}</figure>')
        elif line.strip():
            body.append(f"<p>{_inline(line)}</p>")
    flush()
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + html.escape(title)
            + "</title>\n<style>" + HTML_STYLE + "</style></head><body>\n" + "\n".join(body) + "\n</body></html>\n")
