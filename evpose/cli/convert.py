"""``evpose convert SRC DST.h5``: stream any supported recording into the evpose HDF5 format."""

from __future__ import annotations

import sys
from pathlib import Path

import tyro

from evpose.io.h5 import Compression


def main(
    src: tyro.conf.Positional[Path],
    dst: tyro.conf.Positional[Path],
    width: int | None = None,
    height: int | None = None,
    compression: Compression = Compression.BLOSC_LZ4,
    events_topic: str | None = None,
    imu_topic: str | None = None,
    pose_topic: str | None = None,
    quiet: bool = False,
) -> int:
    """Convert a recording (ECD folder, event h5, ROS1/ROS2 bag, evpose h5) to evpose HDF5, streaming with bounded memory.

    Args:
        src: Input recording.
        dst: Output .h5 file (written atomically; never the input).
        width: Sensor width in pixels, for formats that do not state it (ECD: 240 for the DAVIS240C).
        height: Sensor height in pixels, for formats that do not state it (ECD: 180 for the DAVIS240C).
        compression: Compression of the event columns.
        events_topic: Bag topic of dvs_msgs/EventArray (default: the only/first one).
        imu_topic: Bag topic of sensor_msgs/Imu (default: the first one).
        pose_topic: Bag topic of geometry_msgs/PoseStamped ground truth (default: the first one).
        quiet: No progress bar and no summary line.
    """
    from evpose.errors import InputError
    from evpose.io.convert import convert_to_h5
    from evpose.io.h5 import H5WriteConfig

    from evpose.io.atomic import check_outputs

    check_outputs((dst,), inputs=(src,))  # first: "refusing to overwrite the input" says more than a wrong suffix
    if dst.suffix.lower() not in (".h5", ".hdf5"):
        # `convert rec out.bag` (or an ECD folder name) wrote HDF5 under that name, which `info` then refused as a bag.
        raise InputError(dst, "convert writes evpose HDF5; give an output name ending in .h5")

    opts = {k: v for k, v in (("events_topic", events_topic), ("imu_topic", imu_topic), ("pose_topic", pose_topic)) if v is not None}
    res = convert_to_h5(src, dst, width, height, H5WriteConfig(compression=compression), progress=False if quiet else None, **opts)
    if not quiet:
        print(f"{dst}: {res.events} events from {res.source_format} in {res.seconds:.2f} s ({res.events_per_s / 1e6:.1f} Mev/s)", file=sys.stderr)
    return 0
