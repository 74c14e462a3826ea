"""The experiment folder as a unit: its layout, the saved config's rules, the recipes its
files are made from, their sizes and digests, its maps' facts, one process at a time in it, and the
provenance of its results. Every stage that reads or writes an experiment folder asks
:class:`~curiosity_cli.experiment.experiment.Experiment`.

Nothing is imported here, so that the command line can read a folder's layout without
loading numpy.
"""
