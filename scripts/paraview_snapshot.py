# Render the last step of a run's results.xdmf coloured by von Mises stress, with the walls,
# the way a user sees it in ParaView. Headless:
#   xvfb-run -a pvpython scripts/paraview_snapshot.py OUT/results.xdmf picture.png
# (give the file with a directory part, e.g. ./results.xdmf).
import os
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction,
                             GetScalarBar, OpenDataFile, ResetCamera, SaveScreenshot, Show)

xdmf = sys.argv[1] if len(sys.argv) > 1 else "./out/results.xdmf"
png = sys.argv[2] if len(sys.argv) > 2 else "./von_mises.png"
if not os.path.dirname(xdmf):
    xdmf = "./" + xdmf
particles = OpenDataFile(xdmf)
times = list(particles.TimestepValues)
view = GetActiveViewOrCreate("RenderView")
view.ViewTime = times[-1]
view.OrientationAxesVisibility = 0
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
view.Background = [1.0, 1.0, 1.0]
shown = Show(particles, view)
# flat colours: no shading of the plane
shown.Ambient = 1.0
shown.Diffuse = 0.0
ColorBy(shown, ("CELLS", "von_mises"))
shown.SetScalarBarVisibility(view, True)
lut = GetColorTransferFunction("von_mises")
lut.ApplyPreset("Viridis (matplotlib)", True)
shown.RescaleTransferFunctionToDataRange(False, True)
bar = GetScalarBar(lut, view)
bar.Title = "von Mises [MPa]"
bar.ComponentTitle = ""
bar.WindowLocation = "Any Location"
bar.Position = [0.78, 0.15]
bar.ScalarBarLength = 0.7
bar.ScalarBarThickness = 8
bar.TitleColor = [0.0, 0.0, 0.0]
bar.LabelColor = [0.0, 0.0, 0.0]
bar.TitleFontSize = 5
bar.LabelFontSize = 5
bar.RangeLabelFormat = "%-#.0f"
walls_file = os.path.join(os.path.dirname(xdmf), "walls.xdmf")
if os.path.exists(walls_file):
    walls = Show(OpenDataFile(walls_file), view)
    ColorBy(walls, None)
    walls.AmbientColor = [0.0, 0.0, 0.0]
    walls.DiffuseColor = [0.0, 0.0, 0.0]
    walls.LineWidth = 3.0
view.InteractionMode = "2D"
view.CameraParallelProjection = 1
ResetCamera(view)
SaveScreenshot(png, view, ImageResolution=[900, 700])
print("wrote %s: %d time steps, last t = %g s" % (png, len(times), times[-1]))
