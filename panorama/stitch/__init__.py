"""Stitched panoramas from posed RGB-D views: mono equirect/cubemap and omnidirectional stereo.

In: posed RGB-D :class:`ibr.View` objects (a camera rig, an engine's six cube faces, a walk
through a room) or one RGB-D panorama. Out: equirect or cubemap colour + depth with hole masks,
and ODS eye pairs packed for VR players. Built on the quad-mesh renderer: exact ray casting into
spherical cameras (:mod:`ibr.render.ray_raster`) and N-source blending (:mod:`ibr.render.blend`).
:mod:`~panorama.stitch.baselines` holds the depth-free strip stitching and the mesh slit
stitching that ODS is measured against.
"""

from .fill import fill_panorama, fill_stitched, rim_samples
from .ods import (ODS_LAYOUTS, OdsPair, check_rgbd_panorama, ods_from_panorama, ods_from_views, pack_ods,
                  panorama_views)
from .rgbd import Stitched, stitch_rgbd, stitch_rgbd_cubemap
from .rigs import RigFile, cube_rig, equirect_camera, is_rig_file, ods_cameras, read_rig, ring_rig

__all__ = ["check_rgbd_panorama", "cube_rig", "equirect_camera", "fill_panorama", "fill_stitched",
           "is_rig_file", "ods_cameras", "ods_from_panorama", "ods_from_views", "ODS_LAYOUTS", "OdsPair",
           "pack_ods", "panorama_views", "read_rig", "RigFile", "rim_samples", "ring_rig", "stitch_rgbd",
           "stitch_rgbd_cubemap", "Stitched"]
