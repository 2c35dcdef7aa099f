"""`[output] vtu = "compressed"`: solution.vtu compressed with zlib in blocks, read by an
independent reader (meshio) to the same values, bit for bit, as the raw binary file and the
nodes.csv table of the same run, from the command line and from Python."""

import csv
import subprocess

import meshio
import numpy as np

import memcontact as mc


def solve_cli(cli, case, out, *extra):
    subprocess.run([str(cli), "solve", str(case), "-o", str(out), "-q", *extra], check=True)


def test_compressed_vtu_reads_back_as_the_binary_one(cli, examples, tmp_path):
    case = examples / "liner-slope.toml"
    solve_cli(cli, case, tmp_path / "raw", "--set", "output.plots=[]")
    solve_cli(
        cli, case, tmp_path / "zip", "--set", "output.plots=[]", "--set", 'output.vtu="compressed"'
    )
    raw = meshio.read(tmp_path / "raw" / "solution.vtu")
    packed = meshio.read(tmp_path / "zip" / "solution.vtu")
    head = (tmp_path / "zip" / "solution.vtu").read_bytes()[:400].decode(errors="replace")
    assert 'compressor="vtkZLibDataCompressor"' in head
    assert (tmp_path / "zip" / "solution.vtu").stat().st_size < (
        tmp_path / "raw" / "solution.vtu"
    ).stat().st_size
    np.testing.assert_array_equal(packed.points, raw.points)
    np.testing.assert_array_equal(packed.cells_dict["triangle"], raw.cells_dict["triangle"])
    assert sorted(packed.point_data) == sorted(raw.point_data)
    for name, values in raw.point_data.items():
        np.testing.assert_array_equal(packed.point_data[name], values, err_msg=name)
    for name, values in raw.cell_data.items():
        np.testing.assert_array_equal(packed.cell_data[name][0], values[0], err_msg=name)
    with open(tmp_path / "zip" / "nodes.csv", newline="") as f:
        u = np.array([float(r["u"]) for r in csv.DictReader(f)])
    np.testing.assert_array_equal(packed.point_data["u"], u)


def test_python_writes_a_compressed_result_set(examples, tmp_path):
    result = mc.solve(examples / "disk.toml")
    result.write(tmp_path / "out", vtu="compressed")
    m = meshio.read(tmp_path / "out" / "solution.vtu")
    np.testing.assert_array_equal(m.point_data["u"], result.u)
    np.testing.assert_array_equal(m.points[:, :2], result.mesh.vertices)
    np.testing.assert_array_equal(m.cells_dict["triangle"], result.mesh.triangles)
