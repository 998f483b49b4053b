#!/usr/bin/python3
"""iphong.dask.estimate_normals on a distributed.LocalCluster of 1 and of 2 worker processes
(one thread each): wall time, the speed-up of 2 over 1 and the serial fraction it implies
(Amdahl: f = 2/S - 1), on one synthetic capture, both runs in the same process.

  PYTHONPATH=build/python /usr/bin/python3 bench/dask_speedup.py [--side 384] [--lights 32]
                                                                  [--chunk 96] [--model phong]
"""
import argparse
import time

import numpy as np

import dask.array as da
import distributed
import iphong
import iphong.dask as idask


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--side", type=int, default=384)
    p.add_argument("--lights", type=int, default=32)
    p.add_argument("--chunk", type=int, default=96)
    p.add_argument("--model", default=None, help="None: chosen (the default of iphong normals)")
    a = p.parse_args()
    scene = {"width": a.side, "height": a.side,
             "lights": [{"type": "hemisphere", "count": a.lights, "min_elevation_deg": 30}],
             "objects": [{"shape": "sphere", "radius": 0.95, "subdivisions": 6,
                          "material": {"kd": [0.6, 0.5, 0.4], "ks": 0.3, "shininess": 30}}]}
    capture = iphong.render(scene, per_light=True)
    images = da.from_array(capture["images"], chunks=(-1, a.chunk, a.chunk, -1))
    times, results = {}, {}
    for workers in (1, 2):
        with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            client.scatter([0])  # workers up before the clock starts
            start = time.perf_counter()
            r = idask.estimate_normals(images, capture["light_directions"],
                                       capture["light_intensities"], capture["mask"],
                                       model=a.model)
            plan_seconds = time.perf_counter() - start
            results[workers] = client.compute(r["normals"], sync=True)
            times[workers] = (time.perf_counter() - start, plan_seconds)
    assert np.array_equal(results[1], results[2]), "1 and 2 workers disagree"
    speedup = times[1][0] / times[2][0]
    pixels = int(capture["mask"].sum())
    print(f"{a.side}x{a.side}, {pixels} masked pixels x {a.lights} lights, chunks {a.chunk}^2, "
          f"model {a.model or 'chosen'}")
    print("| workers | wall s | of which the plan (serial) s |")
    print("|---|---|---|")
    for workers in (1, 2):
        print(f"| {workers} | {times[workers][0]:.2f} | {times[workers][1]:.2f} |")
    print(f"speed-up 2 over 1: {speedup:.2f}x; serial fraction (Amdahl) {2 / speedup - 1:.2f}")


if __name__ == "__main__":
    main()
