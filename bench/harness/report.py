"""HTML report: per scene the convergence plot, reference, equal-time images with
crops side by side, false-colour error maps and the relMSE / speed-up table."""

import html
import os

import numpy as np

from . import images, plots


def _fmt(x, digits=4):
    if x is None:
        return "&ndash;"
    if isinstance(x, float):
        return "%.*g" % (digits, x)
    return html.escape(str(x))


def _mean_rel(r):
    """Relative mean difference to the reference (over the pixels the relMSE uses), in %."""
    m = r.get("mean_rel")
    if m is None:
        return "&ndash;"
    se = r.get("mean_rel_stderr")
    return "%+.2f%%" % (100 * m) + (" &plusmn; %.2f" % (100 * se) if se else "")


def _pm(m, se):
    if m is None:
        return "&ndash;"
    if se is None:
        return _fmt(m)
    return "%s &plusmn; %s" % (_fmt(m), _fmt(se, 2))


def _safe(label):
    """File name part for an integrator label such as 'gpt/primal'."""
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in label)


def _cores(r):
    cpu, wall = r.get("cpu_seconds"), r.get("wall_seconds")
    if not cpu or not wall:
        return "&ndash;"
    return "%.2f" % (cpu / wall)


def _rel(path, out):
    return html.escape(os.path.relpath(path, out).replace(os.sep, "/"))


def _trim(arg, scene_value):
    """The run's trimming option, else the scene's."""
    return arg if arg is not None else scene_value


def prepare_scene_assets(tools, scene, summary_rows, rows, integrators, baseline, report_budget,
                         args, crop_count=2):
    """Converts and cuts every image the scene's section shows. Returns a dict of paths."""
    out = args.out
    d = os.path.join(out, "images", scene.name)
    os.makedirs(d, exist_ok=True)
    assets = {"crops": [], "images": {}, "errormaps": {}, "crop_images": {}}
    # Convergence plot (PNG + SVG) in DIR itself.
    base = os.path.join(out, "convergence-%s" % scene.name)
    assets["plot_png"], assets["plot_svg"] = plots.convergence_plot(
        scene.name, summary_rows, base, noise=scene.noise)

    # Equal-time renders: the first seed at the report budget.
    chosen = {}
    for integ in integrators:
        cands = [r for r in rows if r["scene"] == scene.name and r["integrator"] == integ
                 and r["status"] == "ok" and float(r["budget"]) == float(report_budget)]
        cands.sort(key=lambda r: r["seed"])
        if cands:
            chosen[integ] = cands[0]
    assets["equal_time"] = chosen

    ref_png = os.path.join(d, "reference.png")
    tools.convert(scene.reference, ref_png, exposure=scene.exposure)
    ref_pfm = os.path.join(d, "reference.pfm")
    tools.convert(scene.reference, ref_pfm)
    ref = images.read_pfm(ref_pfm)
    os.remove(ref_pfm)

    err_maps = {}
    for integ, r in chosen.items():
        src = os.path.join(out, r["image"])
        png = os.path.join(d, "%s.png" % _safe(integ))
        layer = r.get("layer") or None
        tools.convert(src, png, exposure=scene.exposure, layer=layer)
        pfm = os.path.join(d, "%s.pfm" % _safe(integ))
        tools.convert(src, pfm, layer=layer)
        err_maps[integ] = images.relmse_map(images.read_pfm(pfm), ref)
        os.remove(pfm)
        assets["images"][integ] = png

    # One colour scale for every error map of the scene: the geometric mean over the
    # integrators of each one's 99th percentile of per-pixel relMSE, so neither a much
    # worse nor a much better method makes the others all white or all black.
    key = baseline if baseline in err_maps else (next(iter(err_maps)) if err_maps else None)
    vmax = None
    if key is not None:
        p99 = [float(np.percentile(m, 99.0)) for m in err_maps.values()]
        p99 = [p for p in p99 if p > 0]
        vmax = float(np.exp(np.mean(np.log(p99)))) if p99 else 1.0
        for integ, r in chosen.items():
            fc = os.path.join(d, "%s-error.png" % _safe(integ))
            tools.falsecolor(os.path.join(out, r["image"]), scene.reference, fc, vmax,
                             layer=r.get("layer") or None)
            big = os.path.join(d, "%s-error-big.png" % _safe(integ))
            images.scaled_copy(fc, big)
            assets["errormaps"][integ] = big
    assets["error_max"] = vmax

    # The interactive page (imgtool compare): reference and each equal-time image,
    # with the report's trimming and error scale.
    if chosen:
        integs = [i for i in integrators if i in chosen]
        page = os.path.join(out, "compare", scene.name)
        tools.compare(scene.reference, [os.path.join(out, chosen[i]["image"]) for i in integs], page,
                      ["reference"] + integs, layers=[chosen[i].get("layer") or "" for i in integs],
                      exposure=scene.exposure, error_max=vmax,
                      discard_fraction=_trim(args.discard_fraction, scene.discard_fraction),
                      discard_count=_trim(args.discard_count, scene.discard_count),
                      title="%s: equal time, %g s budget" % (scene.name, float(report_budget)))
        assets["compare"] = os.path.join(page, "index.html")

    # Crops: the scene list's, else where the baseline's error is highest.
    if scene.crops:
        boxes = [list(map(float, b)) for b in scene.crops]
    elif key is not None:
        boxes = images.pick_crops(err_maps[key], count=crop_count)
    else:
        boxes = []
    assets["crops"] = boxes
    framed = os.path.join(d, "reference-framed.png")
    images.framed_copy(ref_png, framed, boxes)
    assets["reference"] = framed
    for label, png in [("reference", ref_png)] + list(assets["images"].items()):
        cut = []
        for i, box in enumerate(boxes):
            p = os.path.join(d, "%s-crop%d.png" % (_safe(label), i))
            images.crop_png(png, p, box)
            cut.append(p)
        assets["crop_images"][label] = cut
    for integ, png in list(assets["images"].items()):
        fr = os.path.join(d, "%s-framed.png" % _safe(integ))
        images.framed_copy(png, fr, boxes)
        assets["images"][integ] = fr
    return assets


CSS = """
body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 1240px; }
h1 { font-size: 1.6em; } h2 { border-bottom: 2px solid #888; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: right; }
th { background: #eee; } td.l, th.l { text-align: left; }
.row { display: flex; flex-wrap: wrap; gap: 10px; align-items: flex-start; }
figure { margin: 0; text-align: center; } figcaption { font-size: 0.85em; }
img.px { image-rendering: pixelated; }
img.full { width: 400px; max-width: 100%; }
.note { color: #555; font-size: 0.9em; } .warn { color: #a40; }
code { background: #f3f3f3; padding: 0 0.2em; }
"""


def _figure(path, out, caption):
    return ('<figure><img class="px full" src="%s" alt="%s"><figcaption>%s</figcaption></figure>'
            % (_rel(path, out), html.escape(caption), html.escape(caption)))


def scene_section(scene, summary_rows, assets, integrators, baseline, report_budget, args,
                  floor_correction):
    out = args.out
    h = ['<section id="scene-%s">' % html.escape(scene.name),
         "<h2>%s</h2>" % html.escape(scene.name)]
    noise = ("%.3g" % scene.noise) if scene.noise is not None else "unknown"
    frac = _trim(args.discard_fraction, scene.discard_fraction)
    cnt = _trim(args.discard_count, scene.discard_count)
    trim = []
    if frac:
        trim.append("highest %.4g%% of pixel errors" % (100 * float(frac)))
    if cnt:
        trim.append("%d highest-error pixels" % int(cnt))
    h.append('<p class="note">scene <code>%s</code><br>reference <code>%s</code>; reference noise '
             'floor (its own relMSE, from <code>%s</code>): <b>%s</b><br>relMSE = mean (X&minus;R)&sup2;'
             '/(R&sup2;+0.001)%s</p>'
             % (html.escape(scene.scene), html.escape(scene.reference or ""),
                html.escape(scene.noise_source or "n/a"), noise,
                ("; trimmed: ignoring the " + " and ".join(trim)) if trim else "; no trimming"))
    if scene.note:
        h.append('<p class="note">%s</p>' % html.escape(scene.note))

    h.append('<div class="row">')
    h.append('<figure><img src="%s" width="560" alt="convergence"><figcaption>relMSE against '
             'render time (log-log; mean &plusmn; stderr over seeds). <a href="%s">SVG</a>'
             '</figcaption></figure>' % (_rel(assets["plot_png"], out), _rel(assets["plot_svg"], out)))
    h.append("</div>")

    # Table.
    h.append("<table><tr><th class=l>integrator</th><th>budget (s)</th><th>runs</th>"
             "<th>render s</th><th>spp</th><th>relMSE</th><th>relMSE &minus; ref noise</th>"
             "<th>relMSE untrimmed</th><th>MSE</th><th>PSNR (dB)</th><th>mean vs ref</th>"
             "<th title=\"CPU seconds of gradus / wall seconds: below the thread count when the "
             "machine was shared\">cores used</th><th>speed-up vs %s</th></tr>"
             % html.escape(baseline))
    for r in sorted(summary_rows, key=lambda r: (integrators.index(r["integrator"])
                                                 if r["integrator"] in integrators else 99,
                                                 r["budget"])):
        if r["integrator"] == baseline:
            sp = "1 (baseline)"
        elif r.get("speedup") is not None:
            sp = "&times;%.2f%s" % (r["speedup"], " (extrapolated)" if r["speedup_extrapolated"]
                                    else "")
        elif r.get("at_noise_floor"):
            sp = '<span class="warn">at noise floor</span>'
        else:
            sp = "&ndash;"
        floor = r.get("ref_noise")
        net = (r["relmse"] - floor) if (floor is not None and r["relmse"] is not None) else None
        net_txt = _fmt(net) if net is None or net > 0 else '<span class="warn">&le; 0</span>'
        h.append("<tr><td class=l>%s</td><td>%s</td><td>%d</td><td>%s</td><td>%s</td><td>%s</td>"
                 "<td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>"
                 % (html.escape(r["integrator"]), _fmt(r["budget"]), r["runs"],
                    _fmt(r["seconds"], 3), _fmt(r["spp"], 5), _pm(r["relmse"], r["relmse_stderr"]),
                    net_txt,
                    _pm(r["relmse_untrimmed"], r["relmse_untrimmed_stderr"]),
                    _pm(r["mse"], r["mse_stderr"]), _pm(r["psnr"], r["psnr_stderr"]),
                    _mean_rel(r), _cores(r), sp))
    h.append("</table>")
    h.append('<p class="note">Speed-up: time %s needs to reach the same relMSE (interpolated on its '
             'log-log curve%s) divided by the integrator\'s render time.</p>'
             % (html.escape(baseline),
                ", after subtracting the reference noise floor" if floor_correction else ""))

    # Equal-time images.
    h.append("<h3>Equal time: %s s budget</h3>" % _fmt(float(report_budget)))
    if assets.get("compare"):
        h.append('<p><a href="%s">Interactive comparison</a>: flip between the images (keys 1-9, '
                 'arrows), zoom and pan them together, exposure, false-colour and relative-error '
                 'views, crops (imgtool compare; needs WebGL2).</p>' % _rel(assets["compare"], out))
    h.append('<div class="row">')
    h.append(_figure(assets["reference"], out, "reference"))
    for integ in integrators:
        if integ in assets["images"]:
            r = assets["equal_time"][integ]
            h.append(_figure(assets["images"][integ], out,
                             "%s: %d spp, %.2f s, relMSE %.4g" % (integ, r["spp"], r["seconds"],
                                                                   r["relmse"])))
    h.append("</div>")
    if assets["crops"]:
        h.append("<h3>Crops</h3><table>")
        labels = ["reference"] + [i for i in integrators if i in assets["images"]]
        h.append("<tr><th></th>" + "".join("<th>%s</th>" % html.escape(l) for l in labels)
                 + "</tr>")
        for c in range(len(assets["crops"])):
            rgb = images.CROP_COLOURS[c % len(images.CROP_COLOURS)]
            h.append('<tr><td style="background: rgb(%d,%d,%d)"></td>'
                     % tuple(int(255 * v) for v in rgb) + "".join(
                '<td><img class="px" src="%s" alt="%s crop %d"></td>'
                % (_rel(assets["crop_images"][l][c], out), html.escape(l), c)
                for l in labels) + "</tr>")
        h.append("</table>")
    if assets["errormaps"]:
        h.append("<h3>Per-pixel relMSE (false colour, white = %s)</h3>" % _fmt(assets["error_max"]))
        h.append('<div class="row">')
        for integ in integrators:
            if integ in assets["errormaps"]:
                h.append(_figure(assets["errormaps"][integ], out, integ))
        h.append("</div>")
    h.append("</section>")
    return "\n".join(h)


def overview_section(summary, scenes, integrators, baseline, report_budget):
    """One table for the whole run: relMSE and speed-up of every integrator per scene at
    the report budget."""
    h = ["<h2>Overview at %s s</h2>" % _fmt(float(report_budget)),
         "<table><tr><th class=l>scene</th><th>ref noise</th>"]
    for integ in integrators:
        h.append("<th>%s relMSE</th>" % html.escape(integ))
        if integ != baseline:
            h.append("<th>%s speed-up</th>" % html.escape(integ))
    h.append("</tr>")
    for s in scenes:
        h.append('<tr><td class=l><a href="#scene-%s">%s</a></td><td>%s</td>'
                 % (html.escape(s.name), html.escape(s.name), _fmt(s.noise, 3)))
        for integ in integrators:
            r = [x for x in summary if x["scene"] == s.name and x["integrator"] == integ
                 and float(x["budget"]) == float(report_budget)]
            r = r[0] if r else None
            h.append("<td>%s</td>" % (_pm(r["relmse"], r["relmse_stderr"]) if r else "&ndash;"))
            if integ != baseline:
                if r and r.get("speedup") is not None:
                    h.append("<td>&times;%.2f%s</td>" % (r["speedup"],
                                                        "*" if r["speedup_extrapolated"] else ""))
                else:
                    h.append("<td>&ndash;</td>")
        h.append("</tr>")
    h.append("</table><p class=note>Speed-up against %s; * = extrapolated beyond %s's measured "
             "curve.</p>" % (html.escape(baseline), html.escape(baseline)))
    return "\n".join(h)


def overhead_section(rows, plot_png, out):
    h = ["<section id=\"overhead\"><h2>Overhead at equal base samples</h2>",
         '<p class="note">Render time of the gradient integrator divided by that of its primal '
         'counterpart at the same spp (G-BDPT paper, Table 1: 5 means gradient and conventional '
         'samples cost the same).</p>',
         "<table><tr><th class=l>scene</th><th class=l>gradient</th><th class=l>primal</th>"
         "<th>spp</th><th>runs</th><th>gradient s</th><th>primal s</th><th>overhead</th></tr>"]
    for r in rows:
        h.append("<tr><td class=l>%s</td><td class=l>%s</td><td class=l>%s</td><td>%d</td>"
                 "<td>%d</td><td>%s</td><td>%s</td><td>&times;%s</td></tr>"
                 % (html.escape(r["scene"]), html.escape(r["gradient"]), html.escape(r["primal"]),
                    r["spp"], r["runs"], _pm(r["gradient_seconds"], r["gradient_seconds_stderr"]),
                    _pm(r["primal_seconds"], r["primal_seconds_stderr"]),
                    _pm(r["overhead"], r["overhead_stderr"])))
    h.append("</table>")
    if plot_png:
        h.append('<img src="%s" width="560" alt="overhead">' % _rel(plot_png, out))
    h.append("</section>")
    return "\n".join(h)


def write_report(path, title, header_items, sections):
    body = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
            "<title>%s</title><style>%s</style></head><body>" % (html.escape(title), CSS),
            "<h1>%s</h1>" % html.escape(title), "<table>"]
    for k, v in header_items:
        body.append('<tr><th class=l>%s</th><td class=l>%s</td></tr>' % (html.escape(k), v))
    body.append("</table>")
    body.extend(sections)
    body.append("</body></html>")
    with open(path, "w") as f:
        f.write("\n".join(body) + "\n")
    return path
