"""Studies: ``curiosity reproduce`` of one experiment end to end (:mod:`~curiosity_cli.study.pipeline`),
of a sweep or a study's specifications (:mod:`~curiosity_cli.study.sweep`,
:mod:`~curiosity_cli.study.specifications`), their report and curve (:mod:`~curiosity_cli.study.report`,
:mod:`~curiosity_cli.study.curve`), and the results of record a study keeps
(:mod:`~curiosity_cli.study.record`), over the types they share (:mod:`~curiosity_cli.study.types`).

This room puts the pipeline's stages together; no stage imports it.
"""
