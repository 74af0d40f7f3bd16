"""The plot of a group run as SVG, standard library only.

Time runs left to right, height bottom to top with a grid line at every floor's level. Each car
is one coloured line: its position over time from its `state` events. Hall calls are triangles
at their floor and the time they were registered: pointing up for a call up, down for a call
down, in grey (the car that answered is the line that reaches the triangle's floor next).
"""

from xml.sax.saxutils import escape

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
           "#17becf"]


def held(trace, t_end):
    """The trace with the car standing between samples: a state event comes when the car moves
    (or something else changes), so a long gap means the car stood at its last position."""
    out = []
    for t, mm in trace:
        if out and t - out[-1][0] > 0.5:
            out.append((t - 0.1, out[-1][1]))
        out.append((t, mm))
    if out:
        out.append((t_end, out[-1][1]))
    return out


def write(path, traces, hall_marks, levels_mm, names, title="", width=1200, height=500):
    """`traces`: car name -> [(t_s, position_mm)]; `hall_marks`: [(t_s, floor, direction)]."""
    left, right, top, bottom = 60, 110, 30, 40
    t_end = max([t for trace in traces.values() for t, _ in trace] +
                [t for t, _, _ in hall_marks] + [1.0])
    low, high = levels_mm[0], levels_mm[-1]
    span = max(high - low, 1)
    plot_w = width - left - right
    plot_h = height - top - bottom

    def x(t):
        return left + plot_w * t / t_end

    def y(mm):
        return top + plot_h * (1 - (mm - low) / span)

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="sans-serif" font-size="12">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{left}" y="18">{escape(title)}</text>']
    for floor, mm in enumerate(levels_mm):
        out.append(f'<line x1="{left}" y1="{y(mm):.1f}" x2="{left + plot_w}" y2="{y(mm):.1f}" '
                   f'stroke="#ddd"/>')
        out.append(f'<text x="{left - 8}" y="{y(mm) + 4:.1f}" text-anchor="end">{floor}</text>')
    step = 60 if t_end > 300 else 30 if t_end > 120 else 10
    t = 0
    while t <= t_end:
        out.append(f'<line x1="{x(t):.1f}" y1="{top + plot_h}" x2="{x(t):.1f}" '
                   f'y2="{top + plot_h + 5}" stroke="black"/>')
        out.append(f'<text x="{x(t):.1f}" y="{top + plot_h + 18}" '
                   f'text-anchor="middle">{t:g}</text>')
        t += step
    out.append(f'<text x="{left + plot_w / 2}" y="{height - 6}" text-anchor="middle">'
               f'time, s</text>')
    for t, floor, direction in hall_marks:
        cx, cy = x(t), y(levels_mm[floor])
        dy = -6 if direction == "up" else 6
        out.append(f'<polygon points="{cx - 4:.1f},{cy - dy / 2:.1f} {cx + 4:.1f},'
                   f'{cy - dy / 2:.1f} {cx:.1f},{cy + dy / 2:.1f}" fill="#888"/>')
    for i, name in enumerate(names):
        colour = COLOURS[i % len(COLOURS)]
        trace = held(traces.get(name, []), t_end)
        if trace:
            points = " ".join(f"{x(t):.1f},{y(mm):.1f}" for t, mm in trace)
            out.append(f'<polyline points="{points}" fill="none" stroke="{colour}" '
                       f'stroke-width="1.5"/>')
        ly = top + 16 * i
        out.append(f'<line x1="{width - right + 10}" y1="{ly}" x2="{width - right + 30}" '
                   f'y2="{ly}" stroke="{colour}" stroke-width="3"/>')
        out.append(f'<text x="{width - right + 35}" y="{ly + 4}">car {escape(name)}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
