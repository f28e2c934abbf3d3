"""``python -m linkwright``: the same as the ``linkwright`` command."""

import sys

from linkwright.cli import main

if __name__ == "__main__":
    sys.exit(main())
