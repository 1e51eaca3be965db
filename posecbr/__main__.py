import sys

from posecbr.cli import main

sys.exit(main())
