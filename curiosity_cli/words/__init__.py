"""Visual words: ORB words, texton words (MR8 filter bank), vocabularies, extraction."""
