"""Per-pixel differences of APC float images (.vti from APCImageFile) against a reference.

    pvpython float_image_diff.py REFERENCE.vti IMAGE.vti [IMAGE.vti ...]

For each image: its sample count (the field array SampleCount: the display rank's), the largest
and mean of the per-pixel largest RGBA difference from the reference, and the share of pixels
over one 8-bit step (1/255). With two images or more, the last two are also compared by their
distance to the reference: how much farther the last is, at most (the stop's check: the
unstopped image, then the stopped one).
"""

import sys

import numpy
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLImageDataReader


def load(path):
    reader = vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    rgba = image.GetPointData().GetArray("RGBA")
    if rgba is None:
        sys.exit("%s: no RGBA array" % path)
    count = image.GetFieldData().GetArray("SampleCount")
    return vtk_to_numpy(rgba).astype(numpy.float64), (count.GetValue(0) if count else -1)


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    ref, ref_samples = load(argv[0])
    print("reference %s: %d samples" % (argv[0], ref_samples))
    errors = []
    for path in argv[1:]:
        image, samples = load(path)
        diff = numpy.abs(image - ref).max(axis=1)
        errors.append(diff)
        print("%s: %d samples, largest %.5f, mean %.6f, over 1/255 %.4f %%"
              % (path, samples, diff.max(), diff.mean(), 100.0 * (diff > 1 / 255).mean()))
    if len(errors) >= 2:
        growth = errors[-1] - errors[-2]
        print("last image farther from the reference than the one before: at most %.5f, "
              "by over 1/255 on %.4f %% of the pixels"
              % (growth.max(), 100.0 * (growth > 1 / 255).mean()))


if __name__ == "__main__":
    main(sys.argv[1:])
