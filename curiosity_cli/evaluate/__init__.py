"""Evaluation: the mutual information of the path labels Z_p with the human labels and with
the batch labels Z_b (``information``, from the label files of :mod:`curiosity_cli.label`),
the tables and statistics of an experiment (the stage that writes them, ``stage``; their
rows, ``rows``; the headline's statistics, ``headline``; reading them back, ``tables``;
``power``, ``replicates``, ``revisits``, ``steering``) and its report (``report``)."""
