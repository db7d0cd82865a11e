"""``python -m canopen_bus``: serve the CAN hub standalone."""

import sys

from canopen_bus.hub import main

sys.exit(main())
