"""What ships with curiosity besides code, as package resources: the configs
(``curiosity_cli.shipped.configs``, the repository's ``configs/``) and the data
(``curiosity_cli.shipped.data``, its ``data/``: vocabularies and embedded maps).
:mod:`curiosity_cli.paths` says where they are."""
