"""Campaigns judged: the campaign report (statistics, re-scoring, Markdown and plots), the
studies flown as campaigns (formations, neighbours, onboard FDIR) and the floor calibration."""
