#!/usr/bin/env python3
"""VTK's dual depth peeling on the same mesh and size as `oit`'s ddp, for issue 12's ratio.

    pip install vtk        # the PyPI wheel; offscreen through EGL or OSMesa (Mesa's llvmpipe)
    python3 bench/local/vtk_ddp.py bunny 512 20       # or a path to an .obj

Every layer is peeled: SetMaximumNumberOfPeels(8) (the bunny has at most 8 at 512² in the
default view) and occlusion ratio 0. Prints the median and range of the frame times in ms,
each frame a Render() finished with a read-back of the pixels (so the GPU work is inside it).
Run it beside `oit render --backend cpu -t ddp --scene bunny --size 512x512`
(or `oit bench ... -t ddp`) in the same minute: the machine's load moves both.
"""
import gzip
import pathlib
import statistics
import sys
import tempfile
import time

import vtk


def main() -> None:
    path = sys.argv[1] if len(sys.argv) > 1 else "bunny"
    builtin = pathlib.Path(__file__).resolve().parents[2] / "oit-core" / "assets" / f"{path}.obj.gz"
    if builtin.is_file():
        # oit's built-in meshes are gzip-compressed OBJ text; VTK's reader wants a file
        tmp = tempfile.NamedTemporaryFile(suffix=".obj", delete=False)
        tmp.write(gzip.decompress(builtin.read_bytes()))
        tmp.close()
        path = tmp.name
    size = int(sys.argv[2]) if len(sys.argv) > 2 else 512
    frames = int(sys.argv[3]) if len(sys.argv) > 3 else 20

    reader = vtk.vtkOBJReader()
    reader.SetFileName(path)
    reader.Update()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(reader.GetOutputPort())
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(0.8, 0.4, 0.2)
    actor.GetProperty().SetOpacity(0.5)
    actor.GetProperty().BackfaceCullingOff()

    renderer = vtk.vtkRenderer()
    renderer.AddActor(actor)
    renderer.SetBackground(0.1, 0.1, 0.1)
    renderer.SetUseDepthPeeling(True)
    renderer.SetMaximumNumberOfPeels(8)
    renderer.SetOcclusionRatio(0.0)

    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(True)
    window.SetSize(size, size)
    window.SetMultiSamples(0)
    window.SetAlphaBitPlanes(True)
    window.AddRenderer(renderer)

    camera = renderer.GetActiveCamera()
    renderer.ResetCamera()
    camera.Azimuth(30)
    camera.Elevation(20)
    renderer.ResetCameraClippingRange()

    window.Render()
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}, {window.ReportCapabilities().splitlines()[0:3]}")
    print(f"dual depth peeling: {bool(renderer.GetLastRenderingUsedDepthPeeling())}")
    grab = vtk.vtkUnsignedCharArray()
    times = []
    for i in range(frames + 2):
        camera.Azimuth(0.01)  # a new view each frame, so nothing is cached
        start = time.perf_counter()
        window.Render()
        window.GetRGBACharPixelData(0, 0, size - 1, size - 1, 0, grab)
        elapsed = (time.perf_counter() - start) * 1e3
        if i >= 2:  # warm-up
            times.append(elapsed)
    print(
        f"{path} {size}x{size}: {frames} frames, median {statistics.median(times):.1f} ms"
        f" (min {min(times):.1f}, max {max(times):.1f})"
    )


if __name__ == "__main__":
    main()
