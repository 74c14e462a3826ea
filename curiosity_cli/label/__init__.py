"""Labelling (``curiosity label``): Z_b per map and Z_p per run, their label files, and
the plan of the blocks of chains that compute them."""
