import sys

from desmon.cli import main

sys.exit(main())
