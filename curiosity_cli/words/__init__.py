"""Visual words: ORB words, texton words (MR8 filter bank), vocabularies, extraction, an experiment's map stores."""
