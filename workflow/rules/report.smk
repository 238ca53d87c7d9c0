# The HTML report's pages (`snakemake --report report.html`): per dataset the paper's
# claims judged (results.md), a results summary from stats.csv, stats.md rendered, and
# the tables as browsable HTML, which the report shows inline (a CSV or Markdown item
# could only be downloaded). The landing
# page, workflow/report/workflow.rst, includes them in that order. Their paths:
# report_pages() in common.smk.


rule report_summary:
    input:
        stats=PROCESSED / "{ds}" / "stats.csv",
        validation=PROCESSED / "{ds}" / "validation.csv",
    output:
        md=PROCESSED / "{ds}" / "summary.md",
        html=report(
            REPORT / "{ds}" / "summary.html",
            caption="../report/summary.rst",
            category="{ds}",
            subcategory="results",
        ),
    log:
        "logs/report/{ds}/summary.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa report summary --stats {input.stats} --dataset {wildcards.ds} "
        "--validation {input.validation} --out-md {output.md} --out-html {output.html} > {log} 2>&1"


rule report_results:
    input:
        unpack(results_input),
        config=CONFIG_FILE,
    output:
        md=PROCESSED / "{ds}" / "results.md",
        html=report(
            REPORT / "{ds}" / "results.html",
            caption="../report/results.rst",
            category="{ds}",
            subcategory="results",
        ),
    log:
        "logs/report/{ds}/results.log",
    conda:
        "../envs/casa.yaml"
    params:
        case_study=case_study_options,
        epsilon=config["simulation"]["epsilon"],
        operator=operator_option,
        provenance=provenance_options,
    shell:
        "exec casa report results --dataset {wildcards.ds} --trials {input.trials} "
        "--steps {input.steps} --stats {input.stats} --likert {input.likert} "
        "--validation {input.validation} {params.case_study} {params.operator} "
        "--epsilon {params.epsilon} "
        "{params.provenance} --out {output.md} --out-html {output.html} > {log} 2>&1"


rule report_stats:
    input:
        md=PROCESSED / "{ds}" / "stats.md",
    output:
        report(
            REPORT / "{ds}" / "stats.html",
            caption="../report/stats.rst",
            category="{ds}",
            subcategory="statistics",
        ),
    log:
        "logs/report/{ds}/stats.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa report markdown {input.md} --out {output} > {log} 2>&1"


rule report_table:
    input:
        PROCESSED / "{ds}" / "{table}.csv",
    output:
        report(
            REPORT / "{ds}" / "{table}.html",
            caption="../report/table.rst",
            category="{ds}",
            subcategory="tables",
        ),
    log:
        "logs/report/{ds}/{table}.log",
    wildcard_constraints:
        table="trials|validation|learning",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa report table {input} --title '{wildcards.ds}: {wildcards.table}.csv' --out {output} "
        "> {log} 2>&1"
