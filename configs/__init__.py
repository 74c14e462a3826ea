"""The shipped configs, a package (``curiosity_cli.shipped.configs``) so the wheel carries them."""
