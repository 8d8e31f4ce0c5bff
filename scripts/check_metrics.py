"""Dev-only: parse a running service's /metrics with the Prometheus project's own
Python parsers (prometheus-client), both the OpenMetrics one and the classic text
one, and print the job counts.

    pip install prometheus-client
    python scripts/check_metrics.py http://127.0.0.1:8080 [KEY]
"""
import sys
import urllib.request

from prometheus_client.openmetrics.parser import text_string_to_metric_families as openmetrics
from prometheus_client.parser import text_string_to_metric_families as classic

url = sys.argv[1].rstrip("/") + "/metrics"
req = urllib.request.Request(url)
if len(sys.argv) > 2:
    req.add_header("Authorization", "Bearer " + sys.argv[2])
text = urllib.request.urlopen(req).read().decode()
families = {f.name: f for f in openmetrics(text)}
classic_names = {f.name for f in classic(text)}
jobs = {s.labels["status"]: s.value for s in families["shapeflow_jobs"].samples}
print("families:", len(families), "(classic parser:", len(classic_names), ")")
print("jobs by status:", jobs)
print("attempts:", families["shapeflow_job_attempts"].samples[0].value)
