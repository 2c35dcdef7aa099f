"""solve_many maps cases over any concurrent.futures-like executor and returns the
results in order, equal to a plain loop."""

import concurrent.futures
import multiprocessing

import numpy as np
import pytest

import memcontact as mc

FIELDS = ["u", "phi", "penetration", "pressure", "contact_force", "state"]


def cases(examples):
    """A small load sweep on the disc, a rigid square and the Gmsh mesh (a file)."""
    out = [
        mc.load_case(examples / "disk.toml", {"membrane.load": f, "mesh.size": 0.2})
        for f in (2.0, 8.0, 20.0)
    ]
    out.append(mc.load_case(examples / "rigid-square.toml", {"mesh.nx": 16, "mesh.ny": 16}))
    out.append(mc.load_case(examples / "gmsh-disk.toml", {"mesh.refine": 0}))
    return out


def assert_same_results(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert x.case == y.case
        for name in FIELDS:
            assert np.array_equal(getattr(x, name), getattr(y, name)), name
        assert x.summary["energy"] == y.summary["energy"]


def test_solve_many_without_executor_is_a_loop(examples):
    cs = cases(examples)
    loop = [mc.solve(c) for c in cs]
    assert_same_results(mc.solve_many(cs), loop)
    # Loads differ, so do the answers (the results really are in order).
    u_max = [r.summary["max_u"] for r in loop[:3]]
    assert u_max == sorted(u_max) and len(set(u_max)) == 3


def test_solve_many_on_a_dask_local_cluster(examples):
    distributed = pytest.importorskip("distributed")
    cs = cases(examples)
    loop = [mc.solve(c) for c in cs]
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        results = mc.solve_many(cs, executor=client)
        # A solve that does not converge comes back as its SolverError.
        stuck = mc.Case({**cs[2].to_dict(), "solver": {"method": "active-set",
                                                        "max_iterations": 1}})
        with pytest.raises(mc.SolverError) as e:
            mc.solve_many([stuck], executor=client)
        assert e.value.result.status == "iteration_limit"
    assert_same_results(results, loop)


def test_solve_many_on_a_process_pool(examples):
    cs = cases(examples)[:3]
    loop = [mc.solve(c) for c in cs]
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        results = mc.solve_many(cs, executor=pool)
    assert_same_results(results, loop)


def test_solve_many_accepts_dicts_and_paths(examples):
    d = mc.load_case(examples / "disk.toml").to_dict()
    r_dict, r_path = mc.solve_many([d, examples / "disk.toml"])
    assert np.array_equal(r_dict.u, r_path.u)
