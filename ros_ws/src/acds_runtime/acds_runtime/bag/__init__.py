"""Writing rosbag2 bags of ACDS runs in lockstep: the writer, its flush policy and its recording marker."""
