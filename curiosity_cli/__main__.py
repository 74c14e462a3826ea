from curiosity_cli.cli import main

main()
