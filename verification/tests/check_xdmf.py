#!/usr/bin/env python3
"""Checks XDMF files against the HDF5 files they reference, reading the HDF5 side with h5dump.

    check_xdmf.py FILE.xmf [FILE.xmf ...]

For every file: the XML parses; h5dump reads each referenced HDF5 file whole (data included); every
HDF DataItem
("file.h5:/path") names a dataset whose shape equals the item's Dimensions and whose type matches
its NumberType and Precision; a Topology's NumberOfElements equals its item's first dimension; and
every cell-centred Attribute has one value per element. Exit status 0 when all hold, 1 otherwise,
with one line per problem naming the file and the dataset; 2 when h5dump cannot be run at all.

Grids may be embedded in collections (a time series: a Temporal collection of Spatial ones); each
Uniform grid is checked as above, and besides: the grids of one collection have distinct Names;
every grid of a Temporal collection has a <Time Value> and the times increase; a Geometry of type
XY (XYZ) has 2 (3) columns; a Polyvertex topology has one node per element; every node-centred
Attribute has one value per geometry point; a Scalar attribute has one component and a Vector
attribute as many as the geometry has coordinates.
"""
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

# XDMF (NumberType, Precision) -> the h5dump names of the matching HDF5 types.
TYPES = {
    ("Float", "8"): {"H5T_IEEE_F64LE", "H5T_IEEE_F64BE"},
    ("Float", "4"): {"H5T_IEEE_F32LE", "H5T_IEEE_F32BE"},
    ("Int", "8"): {"H5T_STD_I64LE", "H5T_STD_I64BE"},
    ("Int", "4"): {"H5T_STD_I32LE", "H5T_STD_I32BE"},
    ("UInt", "8"): {"H5T_STD_U64LE", "H5T_STD_U64BE"},
    ("UInt", "4"): {"H5T_STD_U32LE", "H5T_STD_U32BE"},
}


class NoH5dump(Exception):
    pass


def run_h5dump(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError as e:
        raise NoH5dump(f"cannot run h5dump ({e}); it comes with Debian's hdf5-tools") from e


def h5dump_all(h5_path):
    """Reads the whole file, data included; raises RuntimeError when h5dump fails."""
    run = run_h5dump(["h5dump", h5_path])
    if run.returncode != 0:
        raise RuntimeError(f"h5dump {h5_path} failed ({run.returncode}): {run.stderr.strip()}")


def h5dump_header(h5_path, dataset):
    """h5dump -H output for one dataset; raises RuntimeError when h5dump fails."""
    cmd = ["h5dump", "-H", "-d", dataset, h5_path]
    run = run_h5dump(cmd)
    if run.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({run.returncode}): {run.stderr.strip()}")
    return run.stdout


def dataset_shape_and_type(header):
    dtype = re.search(r"DATATYPE\s+(\S+)", header)
    space = re.search(r"DATASPACE\s+SIMPLE\s*\{\s*\(([^)]*)\)", header)
    if not dtype or not space:
        return None, None
    return [int(x) for x in space.group(1).split(",")], dtype.group(1)


GEOMETRY_COLUMNS = {"XY": 2, "XYZ": 3}


def is_collection(grid):
    return grid.get("GridType") == "Collection" or grid.find("Grid") is not None


def check_collection(grid, where):
    """The collection-level checks: distinct Names; increasing Times in a Temporal collection."""
    problems = []
    children = grid.findall("Grid")
    names = [child.get("Name") for child in children]
    for name in sorted({n for n in names if n is not None and names.count(n) > 1}):
        problems.append(f"{where}: {names.count(name)} grids named '{name}' in collection '{grid.get('Name')}'")
    if grid.get("CollectionType") == "Temporal":
        previous = None
        for k, child in enumerate(children):
            time = child.find("Time")
            try:
                value = float(time.get("Value")) if time is not None else None
            except (TypeError, ValueError):
                value = None
            if value is None:
                problems.append(f"{where}: grid {k} ('{child.get('Name')}') of the Temporal collection has no "
                                f"<Time Value> number")
                continue
            if previous is not None and not value > previous:
                problems.append(f"{where}: time {value} of grid {k} ('{child.get('Name')}') does not follow "
                                f"time {previous} (times must increase)")
            previous = value
    return problems


def check(xmf_path):
    problems = []
    folder = os.path.dirname(os.path.abspath(xmf_path))
    try:
        root = ET.parse(xmf_path).getroot()
    except (ET.ParseError, OSError) as e:
        return [f"{xmf_path}: not readable XML ({e})"]
    if root.tag != "Xdmf":
        problems.append(f"{xmf_path}: the root element is <{root.tag}>, not <Xdmf>")
    read_whole = set()
    n_items = 0
    for grid in root.iter("Grid"):
        if is_collection(grid):
            problems += check_collection(grid, xmf_path)
            continue
        n_elements = None
        topology = grid.find("Topology")
        if topology is not None and topology.get("NumberOfElements"):
            n_elements = int(topology.get("NumberOfElements"))
        if topology is not None and topology.get("TopologyType") == "Polyvertex" \
                and topology.get("NodesPerElement", "1") != "1":
            problems.append(f"{xmf_path}: Polyvertex topology of grid '{grid.get('Name')}' has NodesPerElement "
                            f"{topology.get('NodesPerElement')}, not 1")
        geometry = grid.find("Geometry")
        n_columns = GEOMETRY_COLUMNS.get(geometry.get("GeometryType")) if geometry is not None else None
        n_points = None
        if geometry is not None:
            item = geometry.find("DataItem")
            if item is not None and item.get("Dimensions"):
                n_points = int(item.get("Dimensions").split()[0])
        for parent in grid:
            for item in parent.iter("DataItem"):
                if item.get("Format") != "HDF":
                    continue
                n_items += 1
                ref = (item.text or "").strip()
                if ":" not in ref:
                    problems.append(f"{xmf_path}: DataItem '{ref}' is not FILE:/DATASET")
                    continue
                h5_name, dataset = ref.split(":", 1)
                h5_path = os.path.join(folder, h5_name)
                where = f"{xmf_path}: {h5_name}:{dataset}"
                try:
                    if h5_path not in read_whole:
                        h5dump_all(h5_path)
                        read_whole.add(h5_path)
                    shape, dtype = dataset_shape_and_type(h5dump_header(h5_path, dataset))
                except RuntimeError as e:
                    problems.append(f"{where}: {e}")
                    continue
                if shape is None:
                    problems.append(f"{where}: h5dump shows no simple dataspace and type")
                    continue
                want = [int(x) for x in item.get("Dimensions", "").split()]
                if shape != want:
                    problems.append(f"{where}: shape {shape} in the HDF5 file, Dimensions {want} in the XDMF")
                key = (item.get("NumberType", "Float"), item.get("Precision", "4"))
                if dtype not in TYPES.get(key, set()):
                    problems.append(f"{where}: type {dtype} in the HDF5 file, {key[0]} {key[1]} in the XDMF")
                if parent.tag == "Topology" and n_elements is not None and shape[0] != n_elements:
                    problems.append(f"{where}: {shape[0]} rows for NumberOfElements {n_elements}")
                if parent.tag == "Geometry" and n_columns is not None and shape[-1] != n_columns:
                    problems.append(f"{where}: {shape[-1]} columns for GeometryType {parent.get('GeometryType')}")
                if parent.tag == "Attribute" and parent.get("Center") == "Cell" and n_elements is not None \
                        and shape[0] != n_elements:
                    problems.append(f"{where}: {shape[0]} values for {n_elements} cells")
                if parent.tag == "Attribute" and parent.get("Center") == "Node" and n_points is not None \
                        and shape[0] != n_points:
                    problems.append(f"{where}: {shape[0]} values for {n_points} points")
                if parent.tag == "Attribute":
                    kind = parent.get("AttributeType", "Scalar")
                    n_components = 1 if len(shape) == 1 else shape[-1]
                    if kind == "Scalar" and n_components != 1:
                        problems.append(f"{where}: a Scalar attribute with {n_components} components")
                    if kind == "Vector" and n_columns is not None and (len(shape) != 2 or n_components != n_columns):
                        problems.append(f"{where}: a Vector attribute of shape {shape} on a geometry of "
                                        f"{n_columns} coordinates")
    if n_items == 0:
        problems.append(f"{xmf_path}: no HDF DataItem")
    return problems


def main(paths):
    if not paths:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    problems = []
    for path in paths:
        try:
            found = check(path)
        except NoH5dump as e:
            print(e, file=sys.stderr)
            return 2
        problems += found
        print(f"{path}: {'ok' if not found else f'{len(found)} problem(s)'}")
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
