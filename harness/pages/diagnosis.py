"""The diagnosis of a program (records.ProgramDiagnosis) as the check's overview opens with it,
and as the terminal prints it: the mistakes found, one line each, then the failing cases no
mistake explains with where to look."""
from __future__ import annotations

from html import escape

from ..records import MistakeFound, ProgramDiagnosis


def headline(d: ProgramDiagnosis, cases: int) -> str:
    """"passes every case", or how many mistakes explain how many failing cases."""
    if d.failing_cases == 0:
        return f"Your program passes every case ({cases})."
    mistakes = [m for m in d.mistakes if not m.quirk]
    quirks = len(d.mistakes) - len(mistakes)
    found = (f"{len(mistakes)} mistake{'s' if len(mistakes) != 1 else ''} found"
             if mistakes else "No known mistake found")
    also = f" and {quirks} quirk{'s' if quirks != 1 else ''} of the course program" \
        if quirks else ""
    open_ = f"; {len(d.unexplained)} of them unexplained" if d.unexplained else ""
    return (f"{found}{also} in the {d.failing_cases} failing case"
            f"{'s' if d.failing_cases != 1 else ''} (of {cases}){open_}.")


def explains(m: MistakeFound, failing: int) -> str:
    together = f", some together with {', '.join(m.together)}" if m.together else ""
    return f"explains {len(m.cases)} of the {failing} failing cases{together}"


def diagnosis_html(d: ProgramDiagnosis, cases: int) -> str:
    """The overview's first section."""
    items = "".join(
        f'<li><code class="function">{escape(m.function)}</code>: '
        f"{escape(m.description)} (<code>{escape(m.mistake)}</code>). "
        f"It {escape(explains(m, d.failing_cases))}; clearest in "
        f'<a href="{escape(m.page)}">{escape(m.example)}</a>. Render the reference with it: '
        f"<code>{escape(m.command)}</code></li>" for m in d.mistakes)
    mistakes = f'<ol class="mistakes">{items}</ol>' if items else ""
    rows = "".join(
        f'<li><a href="{escape(c.page)}">{escape(c.case)}</a> ({escape(c.kind)}): '
        + (f"<b>{escape(c.finding.code)}</b>: {escape(c.finding.message)}" if c.finding
           else "no finding") + "</li>" for c in d.unexplained)
    open_ = (f"<h3>Failing cases no known mistake explains ({len(d.unexplained)})</h3>"
             f'<ul class="unexplained">{rows}</ul>' if rows else "")
    cls = "pass" if d.failing_cases == 0 else "fail"
    return (f'<section id="diagnosis"><h2 class="{cls}">{escape(headline(d, cases))}</h2>'
            f"{mistakes}{open_}</section>")


def diagnosis_text(d: ProgramDiagnosis, cases: int) -> str:
    """The same for the terminal, grouped by cause."""
    lines = [headline(d, cases)]
    for i, m in enumerate(d.mistakes, 1):
        lines += [f"  {i}. {m.function}: {m.description} ({m.mistake})",
                  f"     {explains(m, d.failing_cases)}; clearest in {m.example}",
                  f"     {m.command}"]
    if d.unexplained:
        lines.append(f"Failing cases no known mistake explains ({len(d.unexplained)}):")
        for c in d.unexplained:
            said = f"{c.finding.code}: {c.finding.message}" if c.finding else "no finding"
            lines.append(f"  {c.case} ({c.kind}): {said}")
    return "\n".join(lines)
