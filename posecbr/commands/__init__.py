"""One module per ``posecbr`` subcommand; each exposes ``register(subparsers)``."""
