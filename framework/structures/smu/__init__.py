"""External benchmarks on real data (SMU package): four-storey frame and steel footbridge."""
