"""Rendering of report blocks: Markdown (figures linked) and self-contained HTML (figures as
PNG data URIs).  Blocks: ("h1"|"h2"|"h3"|"p"|"pre", text) | ("table", header, rows) |
("img", path, caption)."""

from __future__ import annotations

import base64
import html
from pathlib import Path

__all__ = ["render_markdown", "render_html"]


def render_markdown(blocks, out_dir) -> str:
    out_dir = Path(out_dir)
    lines = []
    for b in blocks:
        kind = b[0]
        if kind in ("h1", "h2", "h3"):
            lines += ["#" * int(kind[1]) + " " + b[1], ""]
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
    return "\n".join(lines).rstrip() + "\n"


_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:0.6em 0;font-size:0.85em}td,th{border:1px solid #bbb;padding:2px 6px}
th{background:#eee}img{max-width:100%;border:1px solid #ddd}figure{margin:1em 0}
figcaption{font-size:0.85em;color:#555}code{background:#f4f4f4}"""


def _inline(text):
    t = html.escape(text)
    parts = t.split("`")
    t = "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))
    parts = t.split("**")
    return "".join(f"<strong>{p}</strong>" if i % 2 else p for i, p in enumerate(parts))


def render_html(blocks, title) -> str:
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>{html.escape(title)}</title>", f"<style>{_CSS}</style></head><body>"]
    for b in blocks:
        kind = b[0]
        if kind in ("h1", "h2", "h3"):
            out.append(f"<{kind}>{_inline(b[1])}</{kind}>")
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
            data = base64.b64encode(Path(b[1]).read_bytes()).decode("ascii")
            out.append(f'<figure><img src="data:image/png;base64,{data}" alt="{html.escape(b[2])}">'
                       f"<figcaption>{_inline(b[2])}</figcaption></figure>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"
