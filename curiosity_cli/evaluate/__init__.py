"""Evaluation: the mutual information of the path labels Z_p with the human labels and with
the batch labels Z_b (``information``, from the label files of :mod:`curiosity_cli.label`),
the tables and statistics of an experiment (``tables``, ``power``, ``replicates``,
``revisits``, ``steering``) and its report (``report``)."""
