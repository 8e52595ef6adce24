# Examples of the kitti area.
