#!/usr/bin/python3
"""Writes tests/fuzz_corpus/vtk: small legacy VTK volumes written by VTK itself (Debian's
python3-vtk9, 9.1), which tests/test_io_vtk.cpp reads and fuzz_vtk starts from.

    /usr/bin/python3 tools/gen_vtk_corpus.py     # from the repository root

File sample i holds (7 i) mod 251, less 100 for signed and float types; u8_colors_* hold 0..255
(VTK writes unsigned char as COLOR_SCALARS: bytes in BINARY, fractions of 255 in ASCII).
"""
import os

import numpy as np
import vtk
from vtk.util import numpy_support

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "fuzz_corpus", "vtk")


def image(dims, vtk_type, np_type, values=None, spacing=(0.5, 1, 2), origin=(-1, 2, 3), name="values"):
    n = dims[0] * dims[1] * dims[2]
    if values is None:
        values = (np.arange(n) * 7) % 251
        if np.dtype(np_type).kind in "if":
            values = values - 100
    img = vtk.vtkImageData()
    img.SetDimensions(*dims)
    img.SetSpacing(*spacing)
    img.SetOrigin(*origin)
    array = numpy_support.numpy_to_vtk(np.asarray(values).astype(np_type), deep=1, array_type=vtk_type)
    array.SetName(name)
    img.GetPointData().SetScalars(array)
    return img


def write(data, name, binary=True, version=None, writer=vtk.vtkStructuredPointsWriter, extent=False):
    w = writer()
    if extent:
        w.SetWriteExtent(True)
    w.SetInputData(data)
    w.SetFileName(os.path.join(OUT, name))
    if binary:
        w.SetFileTypeToBinary()
    if version:
        w.SetFileVersion(version)
    w.Write()


def main():
    os.makedirs(OUT, exist_ok=True)
    write(image((4, 3, 2), vtk.VTK_SHORT, np.int16), "i16_ascii.vtk", binary=False)
    write(image((4, 3, 2), vtk.VTK_SHORT, np.int16), "i16_binary.vtk")
    write(image((5, 4, 3), vtk.VTK_FLOAT, np.float32, spacing=(1, -1, 1)), "f32_binary_v42.vtk", version=42)
    write(image((5, 4, 3), vtk.VTK_DOUBLE, np.float64), "f64_ascii.vtk", binary=False)
    write(image((3, 3, 3), vtk.VTK_UNSIGNED_CHAR, np.uint8), "u8_dataset_binary.vtk", writer=vtk.vtkDataSetWriter)
    # Not the active scalars: written as the first array of a FIELD.
    field = image((4, 3, 2), vtk.VTK_UNSIGNED_SHORT, np.uint16)
    array = field.GetPointData().GetScalars()
    field.GetPointData().SetScalars(None)
    field.GetPointData().AddArray(array)
    write(field, "u16_field_binary.vtk")
    colors = image((16, 16, 1), vtk.VTK_UNSIGNED_CHAR, np.uint8, values=np.arange(256), spacing=(1, 1, 1),
                   origin=(0, 0, 0), name="bytes")
    write(colors, "u8_colors_ascii.vtk", binary=False)
    write(colors, "u8_colors_binary.vtk")
    signed = image((4, 2, 1), vtk.VTK_SIGNED_CHAR, np.int8, values=[-128, -100, -1, 0, 1, 5, 100, 127],
                   spacing=(1, 1, 1), origin=(0, 0, 0), name="s")
    write(signed, "i8_ascii.vtk", binary=False)
    # Field data (written before the geometry): a time, a cycle, strings (one empty, one with a
    # space, one of 70 bytes: a 2-byte length in BINARY), ids (32-bit), 64-bit ints and bits.
    with_field = image((4, 3, 2), vtk.VTK_SHORT, np.int16)
    for cls, name, values in ((vtk.vtkDoubleArray, "TIME", [0.5]), (vtk.vtkIntArray, "CYCLE", [7]),
                              (vtk.vtkStringArray, "NOTE", ["", "hello world", "x" * 70]),
                              (vtk.vtkIdTypeArray, "IDS", [5, 1, 1]), (vtk.vtkLongArray, "LONG", [2, 3]),
                              (vtk.vtkBitArray, "BITS", [1, 0, 1, 1, 0, 0, 1, 0, 1])):
        array = cls()
        array.SetName(name)
        for value in values:
            array.InsertNextValue(value)
        with_field.GetFieldData().AddArray(array)
    write(with_field, "i16_field_data_ascii.vtk", binary=False)
    write(with_field, "i16_field_data_binary.vtk")
    write(with_field, "i16_field_data_binary_v42.vtk", version=42)
    # Cell data too (VTK writes it before the point data): scalars, vectors, ids and a FIELD.
    cells = with_field.GetNumberOfCells()
    for vtk_type, np_type, components, name in ((vtk.VTK_FLOAT, np.float32, 1, "density"),
                                                (vtk.VTK_DOUBLE, np.float64, 3, "flow"),
                                                (vtk.VTK_ID_TYPE, np.int64, 1, "ids")):
        array = numpy_support.numpy_to_vtk(np.arange(cells * components).reshape(cells, components).astype(np_type),
                                           deep=1, array_type=vtk_type)
        array.SetName(name)
        with_field.GetCellData().AddArray(array)
    with_field.GetCellData().SetScalars(with_field.GetCellData().GetArray("density"))
    with_field.GetCellData().SetVectors(with_field.GetCellData().GetArray("flow"))
    write(with_field, "i16_cell_data_ascii.vtk", binary=False)
    write(with_field, "i16_cell_data_binary.vtk")
    write(with_field, "i16_cell_data_binary_v42.vtk", version=42)
    # Arrays with a METADATA block: a vector with one of its three components named (the
    # others' names are blank lines), each with a norm range (INFORMATION); in ASCII its 18
    # values end with a blank line before METADATA, as do the strings.
    meta = image((4, 3, 2), vtk.VTK_SHORT, np.int16)
    cells = meta.GetNumberOfCells()
    flow = numpy_support.numpy_to_vtk(np.arange(cells * 3).reshape(cells, 3).astype(np.float32), deep=1,
                                      array_type=vtk.VTK_FLOAT)
    flow.SetName("flow")
    flow.SetComponentName(1, "vy")
    flow.GetRange(-1)  # records L2_NORM_RANGE in the array's information
    meta.GetCellData().SetVectors(flow)
    labels = vtk.vtkStringArray()
    labels.SetName("labels")
    for i in range(cells):
        labels.InsertNextValue("" if i % 2 else "label %d" % i)
    labels.SetComponentName(0, "text")
    meta.GetCellData().AddArray(labels)
    write(meta, "i16_metadata_ascii.vtk", binary=False)
    write(meta, "i16_metadata_binary.vtk")
    # INFORMATION keys of each kind the reader has to pass: a string vector with an empty string
    # (a blank line inside the METADATA block), an integer (a "DATA 1" line like a vector's
    # count), a string, a double vector; on the cell data, which is skipped.
    info = image((4, 3, 2), vtk.VTK_SHORT, np.int16)
    density = numpy_support.numpy_to_vtk(np.arange(info.GetNumberOfCells()).astype(np.float32), deep=1,
                                         array_type=vtk.VTK_FLOAT)
    density.SetName("density")
    keys = density.GetInformation()
    for text in ("image", "", "label map"):
        vtk.vtkAlgorithm.INPUT_REQUIRED_DATA_TYPE().Append(keys, text)
    keys.Set(vtk.vtkAbstractArray.GUI_HIDE(), 1)
    keys.Set(vtk.vtkDataArray.UNITS_LABEL(), "g/cm3")
    keys.Set(vtk.vtkDataArray.COMPONENT_RANGE(), [0.0, 5.0], 2)
    info.GetCellData().SetScalars(density)
    write(info, "i16_information_ascii.vtk", binary=False)
    write(info, "i16_information_binary.vtk")
    # Written with EXTENT (and a negative spacing): the first sample is at ORIGIN + first * SPACING.
    extent = image((4, 3, 2), vtk.VTK_SHORT, np.int16, spacing=(0.5, -1, 2))
    extent.SetExtent(-3, 0, 4, 6, 1, 2)
    write(extent, "i16_extent_ascii.vtk", binary=False, extent=True)
    write(extent, "i16_extent_binary.vtk", extent=True)


if __name__ == "__main__":
    main()
