"""Evaluation: path labels Z_p and batch labels Z_b (``label_stage``, ``label_sampling``), their mutual
information with the human labels (``information``), the tables and statistics of an experiment
(``tables``, ``power``, ``replicates``, ``revisits``) and its report (``report``)."""
