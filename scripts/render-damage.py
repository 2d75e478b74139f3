"""Renders the concrete damage of a ribbar run on a cut through the ribs.

    pvpython scripts/render-damage.py RESULTS [--step peak|end|N] [--out FILE.png]
                                      [--with-curve] [--size W H]

RESULTS is a scene's results directory (`ribbar-work/<scene>`). The cut is
the plane x = 0, which holds the bar axis and crosses every rib; the
concrete is coloured by its damage D (0 intact, 1 fully damaged), the
steel is grey. With --with-curve the picture also shows the bond
stress-slip curve of the run (σ_mb against FED, from curve.csv) beside it.
Runs in ParaView's Python (pvpython or pvbatch); on a machine without a
display, under `xvfb-run -a`.
"""

import argparse
import os
import sys

from paraview import simple as pv

STEEL = 0  # the `region` cell array of the field files: 0 steel, 1 concrete
CONCRETE = 1


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="the scene's results directory, ribbar-work/<scene>")
    parser.add_argument("--step", default="peak",
                        help="which written state: peak, end or a step number (default peak)")
    parser.add_argument("--out", default=None, help="the PNG written (default RESULTS/damage-STEP.png)")
    parser.add_argument("--with-curve", action="store_true",
                        help="put the bond stress-slip curve beside the damage")
    parser.add_argument("--size", nargs=2, type=int, default=None, metavar=("W", "H"),
                        help="picture size in pixels (default 1000 x 500, 1600 x 500 with the curve)")
    return parser.parse_args()


def bulk_file(results, step):
    name = step if step in ("peak", "end") else "step%04d" % int(step)
    path = os.path.join(results, "fields", name + "_bulk.vtu")
    if not os.path.isfile(path):
        sys.exit("render-damage: %s does not exist (fields are written at the steps "
                 "outputs.fields asks for)" % path)
    return path


def region(source, value):
    """The cells of `source` whose `region` is `value`."""
    threshold = pv.Threshold(Input=source, Scalars=["CELLS", "region"])
    threshold.LowerThreshold = value - 0.5
    threshold.UpperThreshold = value + 0.5
    return threshold


def cut(source):
    """The plane x = 0 through `source`: the bar axis and every rib."""
    plane = pv.Slice(Input=source)
    plane.SliceType = "Plane"
    plane.SliceType.Origin = [0.0, 0.0, 0.0]
    plane.SliceType.Normal = [1.0, 0.0, 0.0]
    return plane


def damage_view(bulk, aspect):
    view = pv.CreateView("RenderView")
    view.OrientationAxesVisibility = 0
    view.Background = [1.0, 1.0, 1.0]
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    concrete = pv.Show(cut(region(bulk, CONCRETE)), view)
    pv.ColorBy(concrete, ("CELLS", "D"))
    lut = pv.GetColorTransferFunction("D")
    lut.ApplyPreset("Cool to Warm", True)
    lut.RescaleTransferFunction(0.0, 1.0)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = "damage D"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    concrete.SetScalarBarVisibility(view, True)
    steel = pv.Show(cut(region(bulk, STEEL)), view)
    steel.ColorArrayName = ["POINTS", ""]
    steel.AmbientColor = steel.DiffuseColor = [0.6, 0.6, 0.65]
    # Seen from +x with y up, the bar axis z runs across the picture,
    # framed on the cut's extent.
    bulk.UpdatePipeline()
    x0, x1, y0, y1, z0, z1 = bulk.GetDataInformation().GetBounds()
    centre = [0.0, 0.5 * (y0 + y1), 0.5 * (z0 + z1)]
    view.CameraFocalPoint = centre
    view.CameraPosition = [centre[0] + 10 * (z1 - z0), centre[1], centre[2]]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 1
    view.CameraParallelScale = 0.55 * max(y1 - y0, (z1 - z0) / aspect)
    return view


def curve_column(results, name):
    """The values of one column of curve.csv."""
    with open(os.path.join(results, "curve.csv")) as f:
        header = f.readline().strip().split(",")
        i = header.index(name)
        return [float(line.split(",")[i]) for line in f if line.strip()]


def max_stress(results):
    return max(curve_column(results, "bond_stress")) * 1e-6


def max_fed(results):
    return max(curve_column(results, "fed")) * 1e3


def curve_view(results):
    table = pv.CSVReader(FileName=[os.path.join(results, "curve.csv")])
    scaled = pv.PythonCalculator(Input=table, ArrayAssociation="Row Data")
    scaled.Expression = "inputs[0].RowData['fed'] * 1e3"
    scaled.ArrayName = "FED (mm)"
    stress = pv.PythonCalculator(Input=scaled, ArrayAssociation="Row Data")
    stress.Expression = "inputs[0].RowData['bond_stress'] * 1e-6"
    stress.ArrayName = "bond stress (MPa)"
    view = pv.CreateView("XYChartView")
    view.LeftAxisTitle = "mean bond stress σ_mb (MPa)"
    view.BottomAxisTitle = "free-end slip FED (mm)"
    view.ShowLegend = 0
    view.LeftAxisUseCustomRange = 1
    view.LeftAxisRangeMinimum = 0.0
    view.LeftAxisRangeMaximum = 1.1 * max(0.0, max_stress(results))
    view.BottomAxisUseCustomRange = 1
    view.BottomAxisRangeMinimum = 0.0
    view.BottomAxisRangeMaximum = 1.05 * max_fed(results)
    shown = pv.Show(stress, view)
    shown.UseIndexForXAxis = 0
    shown.XArrayName = "FED (mm)"
    shown.SeriesVisibility = ["bond stress (MPa)"]
    shown.SeriesColor = ["bond stress (MPa)", "0.1", "0.2", "0.6"]
    shown.SeriesLineThickness = ["bond stress (MPa)", "3"]
    return view


def main():
    args = arguments()
    bulk = pv.XMLUnstructuredGridReader(FileName=[bulk_file(args.results, args.step)])
    out = args.out or os.path.join(args.results, "damage-%s.png" % args.step)
    layout = pv.CreateLayout("ribbar")
    size = args.size or ([1600, 500] if args.with_curve else [1000, 500])
    share = 0.38 if args.with_curve else 0.0
    damage = damage_view(bulk, (1 - share) * size[0] / size[1])
    if args.with_curve:
        cell = layout.SplitHorizontal(0, share)
        layout.AssignView(cell, curve_view(args.results))
        layout.AssignView(cell + 1, damage)
    else:
        layout.AssignView(0, damage)
    layout.SetSize(*size)
    pv.SaveScreenshot(out, layout, ImageResolution=size, TransparentBackground=0)
    print("render-damage: wrote %s" % out)


if __name__ == "__main__":
    main()
