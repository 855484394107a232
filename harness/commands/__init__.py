"""The commands' work: check, grade (and its files), report, stress, autograder, gallery."""
