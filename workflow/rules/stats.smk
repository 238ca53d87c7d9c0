# Per dataset: the statistics of H1-H4 (casa_core.stats), as a table and a report, and
# the participants' cell means they analyse as one wide table (for JASP, SPSS or R).


rule stats:
    input:
        unpack(stats_input),
    output:
        csv=PROCESSED / "{ds}" / "stats.csv",
        md=report(
            PROCESSED / "{ds}" / "stats.md",
            caption="../report/stats.rst",
            category="{ds}",
            subcategory="statistics",
        ),
        wide=PROCESSED / "{ds}" / "wide.csv",
    log:
        "logs/stats/{ds}.log",
    conda:
        "../envs/casa.yaml"
    params:
        likert=likert_option,
        margins=margin_options,
        # Read for the margins only when the config has none (casa stats would take the
        # package's otherwise).
        config=CONFIG_FILE,
    shell:
        "exec casa stats --trials {input.trials} {params.likert} {params.margins} "
        "--validation {input.validation} "
        "--config {params.config} "
        "--out-csv {output.csv} --out-md {output.md} --out-wide {output.wide} > {log} 2>&1"
