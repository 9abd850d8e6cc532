"""Rendering of report blocks: Markdown (figures linked) and self-contained HTML (figures as
PNG data URIs).  Blocks: ("h1"|"h2"|"h3"|"p"|"pre", text) | ("table", header, rows) |
("img", path, caption) | ("gallery", [(path, caption), ...]) |
("toc", [(level, heading text), ...]) (a table of contents linking the headings; both
renderers give every h2/h3 the same GitHub-style anchor).  The HTML has print styles
(@media print): full width, no page break inside a figure or a table, each configuration on a
new page, link targets spelled out in the contents."""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

__all__ = ["render_markdown", "render_html"]


def anchor(text: str) -> str:
    """GitHub's heading anchor: lower case, punctuation dropped, spaces to hyphens."""
    t = re.sub(r"[*`]", "", text).strip().lower()
    t = re.sub(r"[^\w\- ]", "", t)
    return t.replace(" ", "-")


def _anchors(blocks):
    """Unique anchor per h2/h3 (a repeated title gets -1, -2, ... as on GitHub)."""
    seen, out = {}, {}
    for i, b in enumerate(blocks):
        if b[0] in ("h2", "h3"):
            a = anchor(b[1])
            n = seen.get(a, 0)
            seen[a] = n + 1
            out[i] = a if n == 0 else f"{a}-{n}"
    return out


def _toc_targets(blocks, anchors):
    """Heading text → anchor of its first occurrence (for the contents)."""
    out = {}
    for i, a in anchors.items():
        out.setdefault(blocks[i][1], a)
    return out


def render_markdown(blocks, out_dir) -> str:
    out_dir = Path(out_dir)
    anchors = _anchors(blocks)
    targets = _toc_targets(blocks, anchors)
    lines = []
    for b in blocks:
        kind = b[0]
        if kind in ("h1", "h2", "h3"):
            lines += ["#" * int(kind[1]) + " " + b[1], ""]
        elif kind == "toc":
            lines += ["  " * (lvl - 2) + f"- [{text}](#{targets.get(text, anchor(text))})"
                      for lvl, text in b[1] if text != "Contents"] + [""]
        elif kind == "p":
            if b[1]:
                lines += [b[1], ""]
        elif kind == "pre":
            lines += ["```", b[1], "```", ""]
        elif kind == "table":
            head, rows = b[1], b[2]
            lines.append("| " + " | ".join(head) + " |")
            lines.append("|" + "|".join("---" for _ in head) + "|")
            for r in rows:
                lines.append("| " + " | ".join(str(x).replace("|", "\\|") for x in r) + " |")
            lines.append("")
        elif kind == "img":
            rel = Path(b[1]).relative_to(out_dir).as_posix()
            lines += [f"![{b[2]}]({rel})", ""]
        elif kind == "gallery":
            lines += [" ".join(f"![{cap}]({Path(p).relative_to(out_dir).as_posix()})"
                               for p, cap in b[1]), ""]
    return "\n".join(lines).rstrip() + "\n"


_CSS = """\
body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;\
line-height:1.4}
table{border-collapse:collapse;margin:0.6em 0;font-size:0.85em;display:block;overflow-x:auto;\
max-width:100%}
td,th{border:1px solid #bbb;padding:2px 6px;vertical-align:top}
th{background:#eee}img{max-width:100%;height:auto;border:1px solid #ddd}figure{margin:1em 0}
figcaption{font-size:0.85em;color:#555}code{background:#f4f4f4}
nav.toc{background:#f7f7f7;border:1px solid #ddd;padding:0.4em 1em;display:inline-block}
nav.toc ul{margin:0.2em 0;padding-left:1.2em}.provenance{font-size:0.85em;color:#555}
.gallery{display:flex;flex-wrap:wrap;gap:0.6em}.gallery figure{margin:0.3em 0;max-width:48%}
@media print{
body{max-width:none;margin:0;padding:0;font-size:10pt;color:#000}
h2{page-break-before:always;break-before:page}h2#contents,h2#summary{page-break-before:avoid;break-before:auto}
h2,h3{page-break-after:avoid;break-after:avoid}
figure,tr,img{page-break-inside:avoid;break-inside:avoid}
table{display:table;overflow:visible;font-size:8pt}img{max-width:100%;border:none}
a{color:#000;text-decoration:none}nav.toc{border:none;background:none}
}"""


def _bold(t):
    parts = t.split("**")
    if len(parts) % 2 == 0:  # an unpaired ** is text, not markup
        return t
    return "".join(f"<strong>{p}</strong>" if i % 2 else p for i, p in enumerate(parts))


def _inline(text):
    """`code` and **bold** of the Markdown subset; nothing inside a code span is markup
    (``hs**3`` stays as written)."""
    parts = html.escape(text).split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else _bold(p) for i, p in enumerate(parts))


def _figure(path, caption):
    """A figure with its image embedded as a data URI (PNG, or GIF for an animation)."""
    path = Path(path)
    mime = "image/gif" if path.suffix.lower() == ".gif" else "image/png"
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return (f'<figure><img src="data:{mime};base64,{data}" alt="{html.escape(caption)}">'
            f"<figcaption>{_inline(caption)}</figcaption></figure>")


def render_html(blocks, title) -> str:
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>{html.escape(title)}</title>", f"<style>{_CSS}</style></head><body>"]
    anchors = _anchors(blocks)
    targets = _toc_targets(blocks, anchors)
    for i, b in enumerate(blocks):
        kind = b[0]
        if kind in ("h1", "h2", "h3"):
            ident = f' id="{anchors[i]}"' if i in anchors else ""
            out.append(f"<{kind}{ident}>{_inline(b[1])}</{kind}>")
        elif kind == "toc":
            items = "".join(f'<li><a href="#{targets.get(t, anchor(t))}">{_inline(t)}</a></li>'
                            for _, t in b[1] if t != "Contents")
            out.append(f'<nav class="toc"><ul>{items}</ul></nav>')
        elif kind == "p":
            if b[1]:
                out.append(f"<p>{_inline(b[1])}</p>")
        elif kind == "pre":
            out.append(f"<pre>{html.escape(b[1])}</pre>")
        elif kind == "table":
            out.append("<table><tr>" + "".join(f"<th>{_inline(h)}</th>" for h in b[1]) + "</tr>")
            for r in b[2]:
                out.append("<tr>" + "".join(f"<td>{_inline(str(x))}</td>" for x in r) + "</tr>")
            out.append("</table>")
        elif kind == "img":
            out.append(_figure(b[1], b[2]))
        elif kind == "gallery":
            out.append('<div class="gallery">' + "".join(_figure(p, c) for p, c in b[1])
                       + "</div>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"
