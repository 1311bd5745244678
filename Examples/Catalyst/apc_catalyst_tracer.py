# script-version: 2
"""ParaView Catalyst analysis script (a ParaView 5.9+ "v2" script) for apcCatalystMiniApp.

Every rank runs it on its own pieces. It loads the APC plugin, shows the channel "mesh" (the
tracer, a cell array in [0, 1]) with the APC Volume representation over the channel "walls"
(ground and buildings, opaque) and writes a PNG every Nth time step through a PNG extractor.

Settings come from the environment (the mini-app sets them from its options):
  APC_PLUGIN                   the APC plugin library (APC.so)
  APC_CATALYST_EVERY           write every Nth time step (default 100)
  APC_CATALYST_OUTPUT          folder for the images (default catalyst-out)
  APC_CATALYST_REPRESENTATION  "APC Volume" (default) or ParaView's own "Volume"
  APC_CATALYST_SIZE            image width and height (default "640 400")
  APC_CATALYST_TIMINGS         1: rank 0 prints APC's stage times of every rendered step
"""
import os

from paraview import catalyst
from paraview.simple import *  # noqa: F401,F403

EVERY = int(os.environ.get("APC_CATALYST_EVERY", "100"))
OUTPUT = os.environ.get("APC_CATALYST_OUTPUT", "catalyst-out")
REPRESENTATION = os.environ.get("APC_CATALYST_REPRESENTATION", "APC Volume")
SIZE = [int(v) for v in os.environ.get("APC_CATALYST_SIZE", "640 400").split()]
TIMINGS = os.environ.get("APC_CATALYST_TIMINGS") == "1" and REPRESENTATION.startswith("APC")
# The classic mistake, for the tests: every rank rescales the maps to its own data range.
RANK_RANGE = os.environ.get("APC_CATALYST_RANK_RANGE") == "1"

# The plugin must be loaded on every rank before a representation of it is asked for. A
# missing library fails here, at the script's import, on every rank alike.
if REPRESENTATION.startswith("APC"):
    plugin = os.environ.get("APC_PLUGIN", "")
    if not os.path.isfile(plugin):
        raise RuntimeError("APC plugin not found at '%s' (set APC_PLUGIN)" % plugin)
    LoadPlugin(plugin, remote=False, ns=globals())

# One producer per channel the adaptor offers, registered under the channel's name.
mesh = TrivialProducer(registrationName="mesh")
walls = TrivialProducer(registrationName="walls")

view = CreateView("RenderView")
view.ViewSize = SIZE
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.Background = [0.08, 0.09, 0.12]

# Every Nth time step: the extractor's trigger, and the global trigger (which tells the
# adaptor, through RequestDataDescription, to hand over data at all).
png = CreateExtractor("PNG", view, registrationName="PNG")
png.Trigger = "TimeStep"
png.Trigger.Frequency = EVERY
png.Writer.FileName = "tracer_{timestep:06d}.png"
png.Writer.ImageResolution = SIZE

options = catalyst.Options()
options.GlobalTrigger = "TimeStep"
options.GlobalTrigger.Frequency = EVERY
options.ExtractsOutputDirectory = OUTPUT

label = Text(registrationName="label")


def show_walls():
    context = Show(walls, view, "GeometryRepresentation")
    context.Representation = "Surface"
    ColorBy(context, ("CELLS", "patch"))
    patch = GetColorTransferFunction("patch")
    patch.RGBPoints = [0.0, 0.30, 0.31, 0.30, 1.0, 0.82, 0.80, 0.76]
    patch.AutomaticRescaleRangeMode = "Never"
    patch.RescaleTransferFunction(0.0, 1.0)
    context.SetScalarBarVisibility(view, False)


def show_once():
    """Displays need data to colour by: set up at the first step that brings some."""
    # The representation type named: every rank runs this on its own data, and a rank that
    # owns no cells would otherwise get another type (a geometry representation, which has no
    # "APC Volume") than the others and leave them waiting.
    volume = Show(mesh, view, "UnstructuredGridRepresentation")
    volume.Representation = REPRESENTATION
    ColorBy(volume, ("CELLS", "tracer"))
    # A fixed range, the same on every rank. Rescaling to the data would take each rank's own
    # range here (every rank runs this script on its own pieces): each would map differently.
    lut = GetColorTransferFunction("tracer")
    lut.ApplyPreset("Inferno (matplotlib)", True)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, 1.0)
    opacity = GetOpacityTransferFunction("tracer")
    # Clear air where there is no tracer, the plume's thin edges faint, its core dense.
    opacity.Points = [0.0, 0.0, 0.5, 0.0, 0.03, 0.0, 0.5, 0.0, 0.5, 0.08, 0.5, 0.0,
                      1.0, 0.35, 0.5, 0.0]
    opacity.RescaleTransferFunction(0.0, 1.0)
    volume.ScalarOpacityUnitDistance = 4.0
    volume.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(lut, view)
    bar.Title = "tracer"
    bar.ComponentTitle = ""

    # The walls only if the adaptor offers that channel (the same answer on every rank: a
    # channel handed over has a data type even where it is empty).
    if walls.GetDataInformation().GetDataClassName() not in (None, "", "vtkDataObject"):
        show_walls()

    text = Show(label, view)
    text.WindowLocation = "Upper Left Corner"
    text.FontSize = 14

    view.CameraPosition = [-110.0, -230.0, 300.0]
    view.CameraFocalPoint = [160.0, 90.0, 20.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.CameraViewAngle = 30.0


shown = []


def print_timings():
    """APC's stages of the last frame on this rank (the display rank's are the frame's)."""
    from paraview import servermanager
    if servermanager.vtkProcessModule.GetProcessModule().GetPartitionId() != 0:
        return
    display = GetDisplayProperties(mesh, view)
    display.UpdatePropertyInformation()
    # Named fields (the same reading as apcparaview.last_timings, which a Catalyst script
    # may not have on its path): never slots by position.
    names = display.GetProperty("APCLastTimingNames").GetData()
    if isinstance(names, (list, tuple)):
        names = " ".join(names)
    t = dict(zip(names.split(), display.GetProperty("APCLastTimings").GetData()))
    stages = ["agree", "depth", "pass1", "tiles", "allreduce", "pass2", "reduce", "resolve",
              "blend"]
    print("APC stages of the last frame: " + ", ".join(
        "%s %.3f s" % (n, t[n]) for n in stages + ["total"] if n in t), flush=True)


def catalyst_execute(info):
    if not shown:
        show_once()
        shown.append(True)
    elif TIMINGS:
        print_timings()  # the previous step's frame: extractors render after this function
    if RANK_RANGE:
        low, high = mesh.CellData["tracer"].GetRange()  # this rank's own range
        GetColorTransferFunction("tracer").RescaleTransferFunction(low, high)
        GetOpacityTransferFunction("tracer").RescaleTransferFunction(low, high)
    label.Text = "wind tracer, step %d, t = %.1f s (%s)" % (info.timestep, info.time,
                                                           REPRESENTATION)


def catalyst_finalize():
    if TIMINGS and shown:
        print_timings()
