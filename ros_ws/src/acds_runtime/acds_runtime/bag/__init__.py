"""Writing rosbag2 bags of ACDS runs in lockstep: the writer, its flush policy and its recording marker.

The option names below are here, not in :mod:`.writer`, so a command line can offer them without
importing rosbags.
"""

#: Bag storages (``--storage``), MCAP the default.
STORAGE_NAMES = ('mcap', 'sqlite3')
#: ``--compression`` choices; the default is zstd for MCAP (rosbag2's and libmcap's), none for sqlite3.
COMPRESSIONS = ('zstd', 'none')
