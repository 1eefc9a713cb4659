# Parameters: change them and re-run all cells.
VARIANCE_THRESHOLD_CM2 = {{VARIANCE_THRESHOLD_CM2}}  # confident: variance on every axis <= this (cm^2)
VISIBILITY_CUTOFF = {{VISIBILITY_CUTOFF}}  # objects less visible than this fraction are "barely visible"
ACCURATE_CM = {{ACCURATE_CM}}  # accurate: position error <= this (cm)
REPORT_DIR = {{REPORT_DIR}}  # folder with objects.csv, images.csv, summary.json ("." = this notebook's)
