"""Paired CAD/SLAM datasets: building, cleaning, exporting and packing (thesis sec. 4.1).

The packed form (:mod:`map2map.datasets.packed`) is the contract between the dataset
builder and the learning code: one compressed file per dataset that travels with the
code to a GPU machine and loads without PyTorch.
"""
