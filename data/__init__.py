"""The shipped data, a package (``curiosity_cli.shipped.data``) so the wheel carries it."""
