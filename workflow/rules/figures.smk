# Figures: per dataset (objective metrics, Likert answers) and dataset-independent
# (scene, case study, arbitration comparison). `casa figure KIND ... --out STEM`
# writes STEM.pdf and STEM.png.


rule figure_objective:
    input:
        trials=PROCESSED / "{ds}" / "trials.csv",
        stats=PROCESSED / "{ds}" / "stats.csv",
    output:
        pdf=FIGURES / "{ds}" / "objective.pdf",
        png=report(
            FIGURES / "{ds}" / "objective.png",
            caption="../report/objective.rst",
            category="{ds}",
            subcategory="figures",
        ),
    log:
        "logs/figures/{ds}/objective.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=lambda wildcards: FIGURES / wildcards.ds / "objective",
        setup=setup_option,
    shell:
        "exec casa figure objective --trials {input.trials} --stats {input.stats} "
        "{params.setup} --out {params.stem} > {log} 2>&1"


rule figure_likert:
    input:
        likert=PROCESSED / "{ds}" / "likert.csv",
        stats=PROCESSED / "{ds}" / "stats.csv",
    output:
        pdf=FIGURES / "{ds}" / "likert.pdf",
        png=report(
            FIGURES / "{ds}" / "likert.png",
            caption="../report/likert.rst",
            category="{ds}",
            subcategory="figures",
        ),
    log:
        "logs/figures/{ds}/likert.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=lambda wildcards: FIGURES / wildcards.ds / "likert",
        setup=setup_option,
    shell:
        "exec casa figure likert --likert {input.likert} --stats {input.stats} "
        "{params.setup} --out {params.stem} > {log} 2>&1"


rule figure_scene:
    input:
        scene=config["scene"],
    output:
        report(FIGURES / "scene.png", caption="../report/scene.rst", category="scene"),
    log:
        "logs/figures/scene.log",
    conda:
        "../envs/casa.yaml"
    shell:
        "exec casa figure scene --scene {input.scene} --out {output} > {log} 2>&1"


rule figure_arbitration:
    input:
        arbitration=PROCESSED / "case_study" / "arbitration.csv",
    output:
        pdf=FIGURES / "arbitration.pdf",
        png=report(
            FIGURES / "arbitration.png",
            caption="../report/arbitration.rst",
            category="case study",
        ),
    log:
        "logs/figures/arbitration.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=FIGURES / "arbitration",
        epsilon=config["case_study"]["epsilon"],
        setup=setup_option(),
    shell:
        "exec casa figure arbitration --arbitration {input.arbitration} "
        "--epsilon {params.epsilon} {params.setup} --out {params.stem} > {log} 2>&1"


rule figure_case_study:
    input:
        steps=PROCESSED / "case_study" / "steps.csv",
    output:
        pdf=FIGURES / "case_study.pdf",
        png=report(
            FIGURES / "case_study.png",
            caption="../report/case_study.rst",
            category="case study",
        ),
    log:
        "logs/figures/case_study.log",
    conda:
        "../envs/casa.yaml"
    params:
        stem=FIGURES / "case_study",
        epsilon=config["case_study"]["epsilon"],
        setup=setup_option(),
    shell:
        "exec casa figure case_study --steps {input.steps} --epsilon {params.epsilon} "
        "{params.setup} --out {params.stem} > {log} 2>&1"
